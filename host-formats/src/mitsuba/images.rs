//! Image files a scene reads (bitmap textures, environment maps), decoded to linear RGB:
//! OpenEXR, Radiance RGBE (`.hdr`, `.pic`) and PFM as stored (linear floats); PNG and
//! JPEG (8-bit, grey or colour, baseline or progressive) through the sRGB curve unless
//! `raw`, as Mitsuba does. Every file is read through [`super::read_input`] (regular
//! files only, of bounded size) and every header's size is checked before a pixel buffer
//! is made, so a header cannot make the loader allocate without bound.

use std::path::Path;

use ember_core::spectrum::Rgb;
use ember_core::texture::{srgb_decode, srgb_to_linear};

use crate::float_images::{MAX_SIDE, check_dimensions, decode_pfm, decode_rgbe};
use crate::image_io::{ImageErrorKind, RgbImage};

/// The image formats read, for messages.
pub(super) const SUPPORTED: &str = ".png, .jpg/.jpeg, .exr, .hdr/.pic (Radiance RGBE), .pfm";

/// Decode `path` to linear RGB texels, row 0 at the top: OpenEXR, RGBE and PFM as stored;
/// PNG (8 or 16 bits, grey, grey + alpha, RGB, RGBA or palette; alpha dropped) and JPEG
/// (8-bit grey or colour) through the sRGB curve unless `raw`, as Mitsuba does.
pub(super) fn read_image(path: &Path, raw: bool) -> Result<(u32, u32, Vec<Rgb>), String> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let linear = |image: RgbImage| (image.width, image.height, image.pixels.iter().map(|&[r, g, b]| Rgb::new(r, g, b)).collect());
    let bytes = || super::read_input(path).map_err(|e| format!("cannot open: {e}"));
    match ext.as_deref() {
        Some("exr") => Ok(linear(read_exr(path)?)),
        Some("png") => read_png(path, raw),
        Some(e @ ("hdr" | "pic" | "rgbe" | "pfm" | "jpg" | "jpeg")) => decode_image_bytes(e, &bytes()?, raw),
        _ => Err(format!("unsupported image format (supported: {SUPPORTED})")),
    }
}

/// Decode a JPEG, Radiance RGBE or PFM image held in memory, its format named by
/// `extension` (lower case, as a file's): linear RGB texels, row 0 at the top, as
/// [`read_image`] gives them. The fuzz target `image_readers` calls this; it never
/// panics on malformed input.
pub fn decode_image_bytes(extension: &str, bytes: &[u8], raw: bool) -> Result<(u32, u32, Vec<Rgb>), String> {
    let linear = |image: RgbImage| (image.width, image.height, image.pixels.iter().map(|&[r, g, b]| Rgb::new(r, g, b)).collect());
    match extension {
        "hdr" | "pic" | "rgbe" => Ok(linear(decode_rgbe(bytes).map_err(|e| format!("not a readable Radiance RGBE file: {e}"))?)),
        "pfm" => Ok(linear(decode_pfm(bytes).map_err(|e| format!("not a readable PFM file: {e}"))?)),
        "jpg" | "jpeg" => decode_jpeg(bytes, raw),
        _ => Err(format!("unsupported image format (supported: {SUPPORTED})")),
    }
}

/// Most texels (times colour components) a JPEG may decode to per byte of file: a flat
/// 8 × 8 block costs at least about two bits per component (a zero DC difference and an
/// end of block), i.e. 64 samples in a quarter byte, so 4096 leaves a wide margin for
/// real files while a 100-byte header cannot declare a 16384² image.
const MAX_JPEG_EXPANSION: u64 = 4096;

/// Decode a JPEG (baseline or progressive; grey, YCbCr, RGB, CMYK or YCCK, all turned to
/// RGB by the decoder) in strict mode, so damaged entropy data is an error instead of
/// grey blocks, and with the size checked from the header before anything is decoded.
pub(super) fn decode_jpeg(bytes: &[u8], raw: bool) -> Result<(u32, u32, Vec<Rgb>), String> {
    use zune_jpeg::JpegDecoder;
    use zune_jpeg::zune_core::bytestream::ZCursor;
    use zune_jpeg::zune_core::colorspace::ColorSpace;
    use zune_jpeg::zune_core::options::DecoderOptions;
    let options = DecoderOptions::default()
        .set_strict_mode(true)
        .set_max_width(MAX_SIDE as usize)
        .set_max_height(MAX_SIDE as usize)
        .jpeg_set_out_colorspace(ColorSpace::RGB);
    // A file cut short must not decode: the decoder pads a truncated scan with zero bits,
    // so the end-of-image marker must follow the last start-of-scan (entropy-coded data
    // never holds a bare 0xFF 0xD9: a data byte 0xFF is followed by a stuffed 0x00).
    let last_scan = bytes.windows(2).rposition(|w| w == [0xff, 0xda]);
    let end = bytes.windows(2).rposition(|w| w == [0xff, 0xd9]);
    if last_scan.is_some() && end <= last_scan {
        return Err("not a readable JPEG: the file ends before its end-of-image marker (truncated?)".into());
    }
    check_frame_header(bytes)?;
    let mut decoder = JpegDecoder::new_with_options(ZCursor::new(bytes), options);
    decoder.decode_headers().map_err(|e| format!("not a readable JPEG: {e}"))?;
    let info = decoder.info().ok_or("not a readable JPEG: no frame header")?;
    let (width, height) = (info.width as u64, info.height as u64);
    check_dimensions(width, height)?;
    let samples = width * height * info.components.max(1) as u64;
    if samples > (bytes.len() as u64).saturating_mul(MAX_JPEG_EXPANSION) {
        return Err(format!("{width}x{height} pixels cannot be stored in a {}-byte JPEG", bytes.len()));
    }
    let size = decoder.output_buffer_size().ok_or("the image is too large")?;
    let mut rgb = vec![0u8; size];
    decoder.decode_into(&mut rgb).map_err(|e| format!("corrupt JPEG data: {e}"))?;
    if rgb.len() != (width * height * 3) as usize {
        return Err(format!("the decoder gave {} bytes for {width}x{height} RGB pixels", rgb.len()));
    }
    let lut: Vec<f32> = (0..=255u8).map(|v| if raw { v as f32 / 255.0 } else { srgb_to_linear(v) }).collect();
    let texels = rgb.chunks_exact(3).map(|p| Rgb::new(lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize])).collect();
    Ok((width as u32, height as u32, texels))
}

/// Refuse, before decoding, JPEG frame headers that zune-jpeg 0.5.15 does not survive:
/// a component sampled more finely than the first one, or with a factor of 3 (it
/// panicked in its AVX2 inverse DCT on a 16 × 16 frame whose third component was sampled
/// 2 × 3 against the first's 1 × 1, and as well at 2 × 2, 2 × 4, 4 × 2 and 4 × 4; the
/// fuzz target `image_readers` found it, and its input is the committed seed
/// `jpeg_sampling_2x3`; encoders sample the first component, luma, the finest), and a
/// second frame header or start-of-image (a JPEG has one frame). Walks the
/// segments by their lengths and skips entropy-coded data (where 0xFF is followed by a
/// stuffed 0x00 or a restart marker), so an APP segment's embedded thumbnail is not read
/// as a frame. Anything it cannot follow is left to the decoder.
fn check_frame_header(bytes: &[u8]) -> Result<(), String> {
    if !bytes.starts_with(&[0xff, 0xd8]) {
        return Ok(());
    }
    let (mut i, mut frames) = (2usize, 0u32);
    while i + 1 < bytes.len() {
        if bytes[i] != 0xff {
            return Ok(());
        }
        let marker = bytes[i + 1];
        i += 2;
        match marker {
            // Fill bytes before a marker.
            0xff => i -= 1,
            0xd8 => return Err("not a readable JPEG: a second start-of-image marker".into()),
            0xd9 => return Ok(()),
            0x01 | 0xd0..=0xd7 => {}
            _ => {
                let Some(len) = bytes.get(i..i + 2).map(|l| u16::from_be_bytes([l[0], l[1]]) as usize) else { return Ok(()) };
                if matches!(marker, 0xc0..=0xcf) && !matches!(marker, 0xc4 | 0xc8 | 0xcc) {
                    frames += 1;
                    if frames > 1 {
                        return Err("not a readable JPEG: more than one frame header".into());
                    }
                    // After the length (2), precision (1), height (2), width (2) and count
                    // (1): per component its id, sampling h·16 + v and table.
                    let components = bytes.get(i + 8..(i + len).min(bytes.len())).unwrap_or(&[]);
                    let first = components.get(1).map_or((1, 1), |&f| (f >> 4, f & 15));
                    for c in components.chunks_exact(3) {
                        let (h, v) = (c[1] >> 4, c[1] & 15);
                        if h == 3 || v == 3 || h > first.0 || v > first.1 {
                            return Err(format!(
                                "not a readable JPEG: component {} sampled {h}x{v} against the first's {}x{} is not supported",
                                c[0], first.0, first.1
                            ));
                        }
                    }
                }
                i += len;
                if marker == 0xda {
                    // Entropy-coded data runs to the next marker that is not a stuffed
                    // 0xFF 0x00 or a restart marker.
                    while i + 1 < bytes.len() && !(bytes[i] == 0xff && bytes[i + 1] != 0x00 && !(0xd0..=0xd7).contains(&bytes[i + 1])) {
                        i += 1;
                    }
                }
            }
        }
    }
    Ok(())
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
    check_dimensions(width as u64, height as u64)?;
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
