//! The two floating-point image formats that downloaded environment maps and research
//! scenes use besides OpenEXR: Radiance RGBE (`.hdr`, `.pic`) and the Portable Float Map
//! (`.pfm`). Both are small enough to decode here, from bytes in memory, without a crate.
//!
//! **RGBE** (Ward, "Real pixels", Graphics Gems II, 1991). A text header (`#?RADIANCE` or
//! `#?RGBE` first, then `KEY=value` lines, then an empty line) and a resolution line
//! `-Y h +X w` (rows top to bottom, the only orientation written in practice; others are
//! refused by name). A pixel is four bytes r, g, b, e: the value of a channel is
//! `(c + 0.5) · 2^(e − 136)` (Radiance's `colr_color`: mantissa c / 256 with the half-step
//! centre, exponent bias 128), and `e = 0` is black. Scanlines are stored flat, in the
//! old run-length form (a pixel `1 1 1 n` repeats the previous one `n << shift` times,
//! the shift growing by 8 over consecutive repeats), or in the adaptive form Radiance
//! writes for widths 8 to 32767 (`2 2 w_hi w_lo`, then each of the four components in
//! turn as runs: a count above 128 repeats the next byte `count − 128` times, a count
//! up to 128 copies that many bytes).
//!
//! **PFM** (Paul Debevec's HDRShop format). `PF` (three channels) or `Pf` (one) and
//! whitespace, the width and height, and a scale whose sign gives the byte order of the
//! 32-bit floats (negative: little-endian) and whose magnitude is not applied (no reader
//! that matters applies it, Mitsuba included). Exactly one whitespace byte ends the
//! header; rows follow bottom to top, which the reader turns to top to bottom.
//!
//! **Bounds.** Both are refused before any pixel buffer is made when a side exceeds
//! [`MAX_SIDE`] or the texel count [`MAX_TEXELS`]; a PFM must hold exactly its pixel bytes,
//! and an RGBE buffer grows as scanlines decode (its old run-length form can repeat a
//! pixel without bound, so a size checked against the file length would say nothing), so
//! a short or hostile file costs at most what it holds. Every malformed input is an
//! error, never a panic (the tests feed every truncation of valid files).

use crate::image_io::RgbImage;

/// The largest side read, as for PNG textures.
pub const MAX_SIDE: u32 = 1 << 15;
/// The most texels an image may declare: 64 Mpixel (768 MiB as linear f32 RGB), the EXR
/// reader's limit.
pub const MAX_TEXELS: u64 = 1 << 26;

/// Refuse a `width`×`height` image outside the bounds, naming its size.
pub fn check_dimensions(width: u64, height: u64) -> Result<(), String> {
    if width == 0 || height == 0 || width > MAX_SIDE as u64 || height > MAX_SIDE as u64 || width * height > MAX_TEXELS {
        return Err(format!("{width}x{height} pixels (1 to {MAX_SIDE} a side and at most {MAX_TEXELS} in all are supported)"));
    }
    Ok(())
}

/// The header line at `*at` (up to `\n`, which is consumed), as text.
fn line<'a>(bytes: &'a [u8], at: &mut usize, what: &str) -> Result<&'a str, String> {
    let rest = &bytes[*at..];
    let end = rest.iter().position(|&b| b == b'\n').ok_or_else(|| format!("the header ends before its {what}"))?;
    *at += end + 1;
    std::str::from_utf8(&rest[..end]).map_err(|_| format!("the header's {what} is not text"))
}

/// Decode a Radiance RGBE file: linear RGB, row 0 at the top.
pub fn decode_rgbe(bytes: &[u8]) -> Result<RgbImage, String> {
    // Read the header: magic, `KEY=value` lines, an empty line, the resolution.
    let mut at = 0;
    let magic = line(bytes, &mut at, "first line")?;
    if !(magic.starts_with("#?RADIANCE") || magic.starts_with("#?RGBE")) {
        return Err("not a Radiance RGBE file (it must begin with #?RADIANCE or #?RGBE)".into());
    }
    loop {
        let l = line(bytes, &mut at, "empty line")?;
        if l.is_empty() {
            break;
        }
        match l.strip_prefix("FORMAT=").map(str::trim) {
            Some(format) if format != "32-bit_rle_rgbe" => return Err(format!("pixel format \"{format}\" (supported: 32-bit_rle_rgbe)")),
            _ => {}
        }
    }
    let resolution = line(bytes, &mut at, "resolution line")?;
    let fields: Vec<&str> = resolution.split_whitespace().collect();
    let (height, width) = match fields.as_slice() {
        ["-Y", h, "+X", w] => (h.parse::<u64>(), w.parse::<u64>()),
        _ => return Err(format!("resolution line \"{resolution}\" (supported: -Y height +X width, rows top to bottom)")),
    };
    let (Ok(height), Ok(width)) = (height, width) else {
        return Err(format!("resolution line \"{resolution}\": the sizes are not whole numbers"));
    };
    check_dimensions(width, height)?;
    let (w, h) = (width as usize, height as usize);

    // Decode scanline by scanline: the buffers grow with the data read.
    let data = &bytes[at..];
    let mut pos = 0;
    let mut scan = vec![[0u8; 4]; w];
    let mut pixels: Vec<[f32; 3]> = Vec::new();
    for y in 0..h {
        read_scanline(data, &mut pos, &mut scan).map_err(|e| format!("scanline {y} of {h}: {e}"))?;
        pixels.extend(scan.iter().map(|&p| rgbe_to_float(p)));
    }
    Ok(RgbImage { width: width as u32, height: height as u32, pixels })
}

/// One RGBE pixel as linear floats: `(c + 0.5) · 2^(e − 136)`, black for `e = 0`.
pub fn rgbe_to_float([r, g, b, e]: [u8; 4]) -> [f32; 3] {
    if e == 0 {
        return [0.0; 3];
    }
    let f = 2f32.powi(e as i32 - (128 + 8));
    [(r as f32 + 0.5) * f, (g as f32 + 0.5) * f, (b as f32 + 0.5) * f]
}

/// Fill `scan` with the next scanline at `data[*pos..]`, in whichever of the three forms
/// it is stored.
fn read_scanline(data: &[u8], pos: &mut usize, scan: &mut [[u8; 4]]) -> Result<(), String> {
    let w = scan.len();
    let head = data.get(*pos..*pos + 4).ok_or("the file ends inside it")?;
    if (8..=0x7fff).contains(&w) && head[0] == 2 && head[1] == 2 && head[2] & 0x80 == 0 {
        // Adaptive run-length form: the four components one after another.
        let stated = (head[2] as usize) << 8 | head[3] as usize;
        if stated != w {
            return Err(format!("its run-length header says {stated} pixels wide, the image is {w}"));
        }
        *pos += 4;
        for c in 0..4 {
            let mut x = 0;
            while x < w {
                let count = *data.get(*pos).ok_or("the file ends inside it")? as usize;
                *pos += 1;
                if count > 128 {
                    let n = count - 128;
                    let value = *data.get(*pos).ok_or("the file ends inside it")?;
                    *pos += 1;
                    let run = scan.get_mut(x..x + n).ok_or("a run goes past the end of the line")?;
                    run.iter_mut().for_each(|p| p[c] = value);
                    x += n;
                } else {
                    if count == 0 {
                        return Err("a run of length zero".into());
                    }
                    let src = data.get(*pos..*pos + count).ok_or("the file ends inside it")?;
                    let dst = scan.get_mut(x..x + count).ok_or("a run goes past the end of the line")?;
                    dst.iter_mut().zip(src).for_each(|(p, &v)| p[c] = v);
                    *pos += count;
                    x += count;
                }
            }
        }
        return Ok(());
    }
    // Flat pixels, with the old form's repeats (`1 1 1 n`, shifted by 8 per repeat in a row).
    let mut x = 0;
    let mut shift = 0u32;
    while x < w {
        let p: [u8; 4] = data.get(*pos..*pos + 4).ok_or("the file ends inside it")?.try_into().expect("four bytes");
        *pos += 4;
        if p[0] == 1 && p[1] == 1 && p[2] == 1 {
            if x == 0 {
                return Err("a repeat before the first pixel of the line".into());
            }
            let n = (p[3] as usize).checked_shl(shift).filter(|_| shift < 32).ok_or("a repeat too long for the line")?;
            let previous = scan[x - 1];
            let run = scan.get_mut(x..x + n).ok_or("a repeat goes past the end of the line")?;
            run.fill(previous);
            x += n;
            shift += 8;
        } else {
            scan[x] = p;
            x += 1;
            shift = 0;
        }
    }
    Ok(())
}

/// Decode a PFM file (`PF` colour or `Pf` grey, either byte order): linear RGB, row 0 at
/// the top (the file stores the bottom row first).
pub fn decode_pfm(bytes: &[u8]) -> Result<RgbImage, String> {
    // Read the header: three whitespace-separated fields after the magic, then one byte.
    let channels = match bytes.get(..2) {
        Some(b"PF") => 3,
        Some(b"Pf") => 1,
        _ => return Err("not a PFM file (it must begin with PF or Pf)".into()),
    };
    let mut at = 2;
    let mut field = |what: &str| -> Result<&str, String> {
        while bytes.get(at).is_some_and(|b| b.is_ascii_whitespace()) {
            at += 1;
        }
        let start = at;
        while bytes.get(at).is_some_and(|b| !b.is_ascii_whitespace()) {
            at += 1;
        }
        if start == at || at >= bytes.len() {
            return Err(format!("the header ends before its {what}"));
        }
        std::str::from_utf8(&bytes[start..at]).map_err(|_| format!("the header's {what} is not text"))
    };
    let width = field("width")?.parse::<u64>().map_err(|_| "the width is not a whole number".to_string())?;
    let height = field("height")?.parse::<u64>().map_err(|_| "the height is not a whole number".to_string())?;
    let scale = field("scale")?.parse::<f32>().map_err(|_| "the scale is not a number".to_string())?;
    if scale == 0.0 || !scale.is_finite() {
        return Err(format!("scale {scale}: its sign gives the byte order and it must be non-zero and finite"));
    }
    let little = scale < 0.0;
    check_dimensions(width, height)?;
    // Exactly one whitespace byte ends the header (`field` stopped on it).
    let data = &bytes[at + 1..];
    let (w, h) = (width as usize, height as usize);
    let expected = w * h * channels * 4;
    if data.len() != expected {
        return Err(format!("{width}x{height} pixels of {channels} channels need {expected} bytes of data, the file holds {}", data.len()));
    }

    // Convert, turning the bottom-to-top rows over.
    let float = |b: &[u8]| {
        let b: [u8; 4] = b.try_into().expect("four bytes");
        if little { f32::from_le_bytes(b) } else { f32::from_be_bytes(b) }
    };
    let row_bytes = w * channels * 4;
    let mut pixels = Vec::with_capacity(w * h);
    for row in data.chunks_exact(row_bytes).rev() {
        for px in row.chunks_exact(channels * 4) {
            pixels.push(if channels == 3 { [float(&px[0..4]), float(&px[4..8]), float(&px[8..12])] } else { [float(px); 3] });
        }
    }
    Ok(RgbImage { width: width as u32, height: height as u32, pixels })
}

#[cfg(test)]
#[path = "float_images_tests.rs"]
mod tests;
