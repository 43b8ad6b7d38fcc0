use std::path::PathBuf;

/// Everything that can go wrong while building, rendering or saving a figure.
///
/// Each variant names the offending series, axis, cell or file so the caller can tell the
/// user what to fix.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// A series was given no points at all.
    #[error("series '{label}' is empty: give it at least one (x, y) point")]
    EmptySeries {
        /// Legend label of the series.
        label: String,
    },
    /// `xs` and `ys` of a series differ in length.
    #[error(
        "series '{label}' has {xs} x values but {ys} y values: the two slices must be equally long"
    )]
    LengthMismatch {
        /// Legend label of the series.
        label: String,
        /// Number of x values.
        xs: usize,
        /// Number of y values.
        ys: usize,
    },
    /// Every point of a series was NaN, infinite, or non-positive on a log axis.
    #[error(
        "series '{label}' has no plottable point: all {points} points are NaN/infinite or \
         non-positive on a log axis ({detail})"
    )]
    NoPlottablePoints {
        /// Legend label of the series.
        label: String,
        /// Number of points the series had.
        points: usize,
        /// Which axis rejected the values.
        detail: String,
    },
    /// The plot has no series.
    #[error("plot '{title}' has no series: add at least one with .series(...)")]
    NoSeries {
        /// Plot title.
        title: String,
    },
    /// An explicit axis range is unusable.
    #[error("{axis} axis range [{lo}, {hi}] is invalid: {reason}")]
    InvalidRange {
        /// "x" or "y".
        axis: &'static str,
        /// Lower bound given.
        lo: f64,
        /// Upper bound given.
        hi: f64,
        /// Why it was rejected.
        reason: &'static str,
    },
    /// The requested image is too small to hold the axes, labels and legend.
    #[error(
        "image size {width}x{height} px leaves no room for the plot area \
         (needs at least {min_width}x{min_height} px at this font size)"
    )]
    TooSmall {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// Smallest width that would work.
        min_width: u32,
        /// Smallest height that would work.
        min_height: u32,
    },
    /// The requested image would be unreasonably large.
    #[error("image size {width}x{height} px exceeds the limit of {max_pixels} pixels")]
    TooLarge {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// Largest pixel count allowed.
        max_pixels: u64,
    },
    /// An image grid was asked for a cell outside its rows/columns.
    #[error("grid cell ({row}, {col}) is outside the {rows}x{cols} grid")]
    CellOutOfRange {
        /// Requested row.
        row: usize,
        /// Requested column.
        col: usize,
        /// Grid rows.
        rows: usize,
        /// Grid columns.
        cols: usize,
    },
    /// A grid with zero rows or columns, or with no image in any cell.
    #[error("image grid is empty: {0}")]
    EmptyGrid(&'static str),
    /// The raw pixel buffer given for a grid cell has the wrong length.
    #[error("pixel buffer for a {width}x{height} RGB image must hold {expected} bytes, got {got}")]
    BadPixelBuffer {
        /// Image width.
        width: u32,
        /// Image height.
        height: u32,
        /// Bytes needed (width × height × 3).
        expected: usize,
        /// Bytes given.
        got: usize,
    },
    /// Reading or writing a file failed.
    #[error("{action} '{path}': {source}")]
    Io {
        /// What was being done ("writing", "renaming temporary file to", ...).
        action: &'static str,
        /// The file concerned.
        path: PathBuf,
        /// Underlying error.
        source: std::io::Error,
    },
    /// The drawing library failed to draw an element (in practice only when the bundled font
    /// cannot be used).
    #[error("drawing the figure failed: {0}")]
    Drawing(String),
    /// PNG encoding or decoding failed.
    #[error("PNG {action} '{path}': {source}")]
    Image {
        /// "encoding" or "decoding".
        action: &'static str,
        /// The file concerned.
        path: PathBuf,
        /// Underlying error.
        source: image::ImageError,
    },
}

/// Wraps an error of the drawing library.
pub(crate) fn drawing(e: impl std::fmt::Display) -> PlotError {
    PlotError::Drawing(e.to_string())
}
