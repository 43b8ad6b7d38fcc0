//! Small PNG plotting for the lustre project, drawn with `plotters`' bitmap backend.
//!
//! Two figure kinds:
//! * [`Plot`] — publication-style 2-D line plots: linear or log axes with nice ticks, axis
//!   labels (put units in them), several series with colours, line styles and markers, a
//!   legend and a title; PNG via [`Plot::save_png`], the same data as CSV via
//!   [`Plot::save_csv`].
//! * [`ImageGrid`] — labelled image grids (rows × columns with row/column labels and
//!   captions) for model-comparison figures.
//!
//! This crate lays the figure out (frame, wrapped title, labels, legend), chooses the ticks,
//! maps and clips the data; plotters draws axes, grid, ticks, lines, markers and text.
//! Text uses the bundled DejaVu Sans font (Bitstream Vera licence, `fonts/LICENSE-DejaVu.txt`).
//! All files are written atomically (temporary file + rename). Bad data never panics: points
//! that are NaN, infinite or non-positive on a log axis are skipped (and counted in the
//! [`PlotReport`]); an empty series or one with no showable point is an error.
//!
//! ```no_run
//! use plot::{Axis, Plot, Series, LineStyle, Marker};
//! let theta: Vec<f64> = (0..90).map(f64::from).collect();
//! let ggx: Vec<f64> = theta.iter().map(|t| (-t / 10.0).exp()).collect();
//! Plot::new("Cu, 550 nm, θi = 0°")
//!     .x_axis(Axis::linear("θo [deg]"))
//!     .y_axis(Axis::log("BRDF [sr⁻¹]"))
//!     .series(Series::line("GGX", &theta, &ggx))
//!     .series(Series::points("measured", &theta, &ggx).marker(Marker::Square).marker_every(10))
//!     .save_png("brdf.png", 800, 600)?;
//! # Ok::<(), plot::PlotError>(())
//! ```
#![deny(missing_docs)]

mod axis;
mod backend;
mod color;
mod csv;
mod error;
mod grid;
mod io;
mod plot;
mod series;
mod stroke;
mod text;
mod ticks;

pub use axis::{Axis, AxisMap, Scale};
pub use color::Rgb;
pub use csv::{series_csv, write_series_csv};
pub use error::PlotError;
pub use grid::{GridLayout, ImageGrid};
pub use image::{Rgb as Rgb8, RgbImage};
pub use io::{load_rgb, save_png, write_atomic};
pub use plot::{Legend, Plot, PlotReport, PxRect, Skipped};
pub use series::{LineStyle, Marker, Series};
pub use ticks::{Tick, linear_ticks, log_ticks};
