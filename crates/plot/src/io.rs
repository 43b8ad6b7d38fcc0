//! Atomic file output: everything is written to a temporary file in the destination folder
//! and renamed over the target, so a crash never leaves a half-written PNG or CSV.

use crate::PlotError;
use image::{ExtendedColorType, ImageEncoder, RgbImage, codecs::png::PngEncoder};
use std::path::Path;

/// Writes `bytes` to `path` atomically (temporary file in the same folder + rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), PlotError> {
    safe_io::write_atomic(path, bytes).map_err(|e| PlotError::Io {
        action: e.action,
        path: e.path,
        source: e.source,
    })
}

/// Encodes an RGB image as PNG in memory.
pub fn encode_png(img: &RgbImage, path_for_errors: &Path) -> Result<Vec<u8>, PlotError> {
    let mut buf = Vec::new();
    PngEncoder::new(&mut buf)
        .write_image(
            img.as_raw(),
            img.width(),
            img.height(),
            ExtendedColorType::Rgb8,
        )
        .map_err(|source| PlotError::Image {
            action: "encoding",
            path: path_for_errors.to_path_buf(),
            source,
        })?;
    Ok(buf)
}

/// Saves an RGB image as PNG, atomically.
pub fn save_png(img: &RgbImage, path: impl AsRef<Path>) -> Result<(), PlotError> {
    let path = path.as_ref();
    write_atomic(path, &encode_png(img, path)?)
}

/// Loads a PNG (or any format the `image` crate was built with) as 8-bit RGB.
pub fn load_rgb(path: impl AsRef<Path>) -> Result<RgbImage, PlotError> {
    let path = path.as_ref();
    let img = image::open(path).map_err(|source| match source {
        image::ImageError::IoError(e) => PlotError::Io {
            action: "reading",
            path: path.to_path_buf(),
            source: e,
        },
        other => PlotError::Image {
            action: "decoding",
            path: path.to_path_buf(),
            source: other,
        },
    })?;
    Ok(img.to_rgb8())
}
