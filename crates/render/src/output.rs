//! Writing images and films atomically: a temporary file in the target's
//! directory, then a rename, so a reader never sees a half-written file and an
//! interrupted write leaves the previous version intact.

use crate::color::to_u8;
use crate::error::RenderError;
use crate::film::BandLayout;
use std::path::Path;

/// Writes `bytes` to `path` atomically (temporary file, sync, rename),
/// creating the folder if missing (renders name output folders freely).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), RenderError> {
    safe_io::create_parent(path).map_err(|e| RenderError::io(&e.path, e.source))?;
    safe_io::write_atomic(path, bytes).map_err(|e| RenderError::io(path, e.source))
}

/// Writes a linear-sRGB float EXR (channels R, G, B; f32).
pub fn write_exr(
    path: &Path,
    width: u32,
    height: u32,
    rgb: &[[f32; 3]],
) -> Result<(), RenderError> {
    use exr::prelude::*;
    let w = width as usize;
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let p = rgb[y * w + x];
        (p[0], p[1], p[2])
    });
    let image = Image::from_channels((w, height as usize), channels);
    let mut bytes = std::io::Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| RenderError::Image {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
    write_atomic(path, bytes.get_ref())
}

/// Writes a linear-sRGB float EXR with spectral bands: channels R, G, B
/// (f32, `rgb`) and one f32 channel per band of `layout` named as pbrt-v4's
/// `SpectralFilm` names them (`S0.374,688nm`, [`BandLayout::channel_name`]),
/// `bands` holding the pixels' band values band by band within a pixel,
/// pixels row-major. The header carries pbrt's `spectralLayoutVersion` "1.0"
/// and `emissiveUnits` "W.m^-2.sr^-1" (the OpenEXR spectral layout); the
/// bands are in the unit of the scene's radiance per nm.
pub fn write_exr_spectral(
    path: &Path,
    width: u32,
    height: u32,
    rgb: &[[f32; 3]],
    layout: &BandLayout,
    bands: &[f32],
) -> Result<(), RenderError> {
    use exr::prelude::*;
    let n = layout.len();
    let image_error = |message: String| RenderError::Image {
        path: path.to_path_buf(),
        message,
    };
    if rgb.len() as u64 != width as u64 * height as u64 || bands.len() != rgb.len() * n {
        return Err(image_error(format!(
            "{} RGB and {} band values for {width}×{height} pixels × {n} bands",
            rgb.len(),
            bands.len()
        )));
    }
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        let v = rgb.iter().map(|p| p[c]).collect();
        list.push(AnyChannel::new(name, FlatSamples::F32(v)));
    }
    for b in 0..n {
        let v = bands.iter().skip(b).step_by(n).copied().collect();
        list.push(AnyChannel::new(
            layout.channel_name(b).as_str(),
            FlatSamples::F32(v),
        ));
    }
    // One custom attribute per map: the writer emits a map in its (random)
    // iteration order, and the file must not depend on the process.
    let text = |v: &str| AttributeValue::Text(Text::from(v));
    let mut attributes = LayerAttributes::default();
    attributes
        .other
        .insert(Text::from("emissiveUnits"), text("W.m^-2.sr^-1"));
    let layer = Layer::new(
        (width as usize, height as usize),
        attributes,
        Encoding::default(),
        AnyChannels::sort(list),
    );
    let mut image = Image::from_layer(layer);
    image
        .attributes
        .other
        .insert(Text::from("spectralLayoutVersion"), text("1.0"));
    let mut bytes = std::io::Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| image_error(e.to_string()))?;
    write_atomic(path, bytes.get_ref())
}

/// Writes an 8-bit sRGB PNG (values clamped to [0, 1] before encoding).
pub fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    rgb: &[[f32; 3]],
) -> Result<(), RenderError> {
    let buf: Vec<u8> = rgb
        .iter()
        .flat_map(|p| p.map(|v| to_u8(v as f64)))
        .collect();
    let mut bytes = std::io::Cursor::new(Vec::new());
    image::write_buffer_with_format(
        &mut bytes,
        &buf,
        width,
        height,
        image::ExtendedColorType::Rgb8,
        image::ImageFormat::Png,
    )
    .map_err(|e| RenderError::Image {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    write_atomic(path, bytes.get_ref())
}

/// Reads back a float RGB EXR as (width, height, pixels); used by tests and tools.
pub fn read_exr(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>), RenderError> {
    use exr::prelude::*;
    let img = read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![[0f32; 3]; res.width() * res.height()]),
        |px: &mut (usize, Vec<[f32; 3]>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px.1[pos.y() * px.0 + pos.x()] = [r, g, b];
        },
    )
    .map_err(|e| RenderError::Image {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let size = img.layer_data.size;
    Ok((
        size.width() as u32,
        size.height() as u32,
        img.layer_data.channel_data.pixels.1,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exr_and_png_round_trip() {
        let dir = std::env::temp_dir().join(format!("lustre-output-test-{}", std::process::id()));
        let rgb: Vec<[f32; 3]> = (0..6).map(|i| [i as f32, 0.5, -1.0]).collect();
        let exr = dir.join("a.exr");
        write_exr(&exr, 3, 2, &rgb).unwrap();
        let (w, h, back) = read_exr(&exr).unwrap();
        assert_eq!((w, h), (3, 2));
        assert_eq!(back, rgb);
        let png = dir.join("a.png");
        write_png(&png, 3, 2, &rgb).unwrap();
        let bytes = std::fs::read(&png).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        // No temporary files left behind.
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 2);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
