//! Texture plugins: `bitmap` (PNG or OpenEXR) and `checkerboard`, with Mitsuba 3's
//! parameter names and defaults. The files are decoded here; the core gets linear texels
//! ([`ember_core::texture`] has the lookup conventions).

use std::path::Path;

use ember_core::spectrum::Rgb;
use ember_core::texture::{Bitmap, Texture, UvTransform, WrapMode, srgb_decode, srgb_to_linear};
use glam::DMat4;

use crate::image_io::{ImageErrorKind, RgbImage};

use super::build::Ctx;
use super::props::Props;
use super::{Fail, Res};

/// The largest bitmap side read.
const MAX_SIDE: u32 = 1 << 15;
/// The most texels a PNG may declare: 64 Mpixel (768 MiB as linear f32 RGB), the EXR
/// reader's limit, so a header cannot make the loader allocate without bound.
const MAX_TEXELS: u64 = 1 << 26;

impl Ctx<'_> {
    /// The texture of object `idx`: its id in the scene and its mean colour, built once
    /// and shared by every material that refers to it.
    pub(crate) fn texture(&mut self, idx: usize) -> Res<(u32, Rgb)> {
        if let Some(&t) = self.textures.get(&idx) {
            return Ok(t);
        }
        let obj = self.obj(idx)?;
        self.mark(idx);
        self.no_children(obj)?;
        let mut p = Props::new(obj);
        let texture = match obj.kind.as_str() {
            "checkerboard" => {
                let color0 = p.color("color0", Rgb::splat(0.4))?;
                let color1 = p.color("color1", Rgb::splat(0.2))?;
                for (name, c) in [("color0", color0), ("color1", color1)] {
                    if !c.is_valid_radiance() {
                        return Err(Fail::at(p.loc_of(name), format!("`{name}` must be non-negative and finite")));
                    }
                }
                Texture::Checkerboard { color0, color1, to_uv: to_uv(&mut p)? }
            }
            "bitmap" => {
                let file_loc = p.loc_of("filename");
                let filename = p.string_opt("filename")?.ok_or_else(|| Fail::at(obj.loc, "the bitmap needs a `filename` (PNG or OpenEXR)"))?;
                let bilinear = match p.string_opt("filter_type")? {
                    None | Some("bilinear") => true,
                    Some("nearest") => false,
                    Some(other) => return Err(Fail::at(p.loc_of("filter_type"), format!("unknown filter_type \"{other}\" (supported: bilinear, nearest)"))),
                };
                let wrap = match p.string_opt("wrap_mode")? {
                    None | Some("repeat") => WrapMode::Repeat,
                    Some("mirror") => WrapMode::Mirror,
                    Some("clamp") => WrapMode::Clamp,
                    Some(other) => return Err(Fail::at(p.loc_of("wrap_mode"), format!("unknown wrap_mode \"{other}\" (supported: repeat, mirror, clamp)"))),
                };
                let raw = p.bool("raw", false)?;
                let to_uv = to_uv(&mut p)?;
                let path = self.base_dir.join(filename);
                self.inputs.push(path.clone());
                let (w, h, texels) = read_image(&path, raw).map_err(|e| Fail::at(file_loc, format!("bitmap \"{}\": {e}", path.display())))?;
                let bitmap = Bitmap::new(w, h, texels, wrap, bilinear).map_err(|e| Fail::at(file_loc, format!("bitmap \"{}\": {e}", path.display())))?;
                Texture::Bitmap { bitmap, to_uv }
            }
            other => return Err(Fail::at(obj.loc, format!("unsupported texture type \"{other}\" (supported: bitmap, checkerboard)"))),
        };
        p.finish()?;
        let mean = texture.mean();
        let id = self.sb.add_texture(texture);
        self.textures.insert(idx, (id, mean));
        Ok((id, mean))
    }
}

/// Mitsuba's `to_uv` (an affine map of the uv plane): the 4 × 4 transform's upper-left
/// 2 × 2 block and the x, y of its translation.
fn to_uv(p: &mut Props) -> Res<UvTransform> {
    let loc = p.loc_of("to_uv");
    let m: DMat4 = p.transform("to_uv")?;
    let t =
        UvTransform { x: m.x_axis.truncate().truncate().as_vec2(), y: m.y_axis.truncate().truncate().as_vec2(), t: m.w_axis.truncate().truncate().as_vec2() };
    if ![t.x, t.y, t.t].iter().all(|v| v.is_finite()) {
        return Err(Fail::at(loc, "`to_uv` is not finite"));
    }
    Ok(t)
}

/// Decode `path` to linear RGB texels, row 0 at the top: OpenEXR as stored; PNG (8 or 16
/// bits, grey, grey + alpha, RGB, RGBA or palette; alpha dropped) through the sRGB curve
/// unless `raw`, as Mitsuba does.
fn read_image(path: &Path, raw: bool) -> Result<(u32, u32, Vec<Rgb>), String> {
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
