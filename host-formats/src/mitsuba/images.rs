//! Image files a scene reads (bitmap textures, environment maps): PNG and OpenEXR
//! decoded to linear RGB, through [`super::read_input`] (regular files only, of bounded
//! size) and with bounded sizes, so a header cannot make the loader allocate without
//! bound.

use std::path::Path;

use ember_core::spectrum::Rgb;
use ember_core::texture::{srgb_decode, srgb_to_linear};

use crate::image_io::{ImageErrorKind, RgbImage};

/// The largest bitmap side read.
const MAX_SIDE: u32 = 1 << 15;
/// The most texels a PNG may declare: 64 Mpixel (768 MiB as linear f32 RGB), the EXR
/// reader's limit, so a header cannot make the loader allocate without bound.
const MAX_TEXELS: u64 = 1 << 26;

/// Decode `path` to linear RGB texels, row 0 at the top: OpenEXR as stored; PNG (8 or 16
/// bits, grey, grey + alpha, RGB, RGBA or palette; alpha dropped) through the sRGB curve
/// unless `raw`, as Mitsuba does.
pub(super) fn read_image(path: &Path, raw: bool) -> Result<(u32, u32, Vec<Rgb>), String> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("exr") => {
            let image = read_exr(path)?;
            Ok((image.width, image.height, image.pixels.iter().map(|&[r, g, b]| Rgb::new(r, g, b)).collect()))
        }
        Some("png") => read_png(path, raw),
        _ => Err("unsupported image format (supported: .png, .exr)".into()),
    }
}

/// An OpenEXR file's first RGB layer, read through [`super::read_input`] (a regular file
/// only, of bounded size) and decoded from memory.
pub(crate) fn read_exr(path: &Path) -> Result<RgbImage, String> {
    let bytes = super::read_input(path).map_err(|e| format!("cannot open: {e}"))?;
    // The decoder names the file `<memory>`; the caller's message names it.
    crate::image_io::read_exr_from_bytes(&bytes).map_err(|e| match e.kind {
        ImageErrorKind::Exr(e) => format!("not a readable OpenEXR file: {e}"),
        _ => e.to_string(),
    })
}

fn read_png(path: &Path, raw: bool) -> Result<(u32, u32, Vec<Rgb>), String> {
    let bytes = super::read_input(path).map_err(|e| format!("cannot open: {e}"))?;
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    // Palette and sub-byte grey become 8-bit; 16-bit samples stay 16-bit.
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(|e| format!("not a readable PNG: {e}"))?;
    let (width, height) = (reader.info().width, reader.info().height);
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE || width as u64 * height as u64 > MAX_TEXELS {
        return Err(format!("{width}x{height} pixels (1 to {MAX_SIDE} a side and at most {MAX_TEXELS} in all are supported)"));
    }
    let size = reader.output_buffer_size().ok_or("the image is too large")?;
    let mut buf = vec![0u8; size];
    let frame = reader.next_frame(&mut buf).map_err(|e| format!("corrupt PNG data: {e}"))?;
    let (color, depth) = reader.output_color_type();
    let channels = match color {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => return Err("an indexed PNG the decoder did not expand".into()),
    };
    let bytes = match depth {
        png::BitDepth::Eight => 1,
        png::BitDepth::Sixteen => 2,
        other => return Err(format!("unsupported bit depth {other:?}")),
    };
    let data = &buf[..frame.buffer_size()];
    let decode = |v: f32| if raw { v } else { srgb_decode(v) };
    // 8-bit values through the exact table of the core, 16-bit ones through the curve.
    let lut: Vec<f32> = (0..=255u8).map(|v| if raw { v as f32 / 255.0 } else { srgb_to_linear(v) }).collect();
    let sample =
        |px: &[u8], c: usize| -> f32 { if bytes == 1 { lut[px[c] as usize] } else { decode(u16::from_be_bytes([px[2 * c], px[2 * c + 1]]) as f32 / 65535.0) } };
    let stride = channels * bytes;
    let row = frame.line_size;
    let mut texels = Vec::with_capacity(width as usize * height as usize);
    for y in 0..height as usize {
        for x in 0..width as usize {
            let px = &data[y * row + x * stride..y * row + (x + 1) * stride];
            texels.push(if channels < 3 { Rgb::splat(sample(px, 0)) } else { Rgb::new(sample(px, 0), sample(px, 1), sample(px, 2)) });
        }
    }
    Ok((width, height, texels))
}
