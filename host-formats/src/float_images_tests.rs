//! RGBE and PFM decoding: files written byte by byte here, in every storage form, decoded
//! to known values; damaged and hostile files refused, never a panic.

use super::*;

/// A 9 × 2 image of RGBE pixels (9 wide, so the adaptive run-length form applies):
/// row 0 has a run of five equal pixels, row 1 varies.
fn rgbe_pixels() -> Vec<[u8; 4]> {
    let mut p = vec![[128, 64, 0, 129]; 5];
    p.extend([[255, 255, 255, 136], [1, 2, 3, 100], [0, 0, 0, 0], [200, 10, 20, 130]]);
    p.extend((0..9u8).map(|i| [i * 20, 255 - i * 20, 7, 120 + i]));
    p
}

fn rgbe_header(width: usize, height: usize) -> Vec<u8> {
    format!("#?RADIANCE\n# made by a test\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1.0\n\n-Y {height} +X {width}\n").into_bytes()
}

/// The three storage forms of `rgbe_pixels`: flat, old run-length (the five equal pixels
/// as one and a repeat of four), adaptive run-length (runs and copies per component).
fn rgbe_files() -> [Vec<u8>; 3] {
    let p = rgbe_pixels();
    let mut flat = rgbe_header(9, 2);
    p.iter().for_each(|px| flat.extend(px));

    let mut old = rgbe_header(9, 2);
    old.extend(p[0]);
    old.extend([1, 1, 1, 4]);
    p[5..].iter().for_each(|px| old.extend(px));

    let mut adaptive = rgbe_header(9, 2);
    for row in p.chunks(9) {
        adaptive.extend([2, 2, 0, 9]);
        for c in 0..4 {
            // A run of the first five bytes where they are equal, copies otherwise.
            let values: Vec<u8> = row.iter().map(|px| px[c]).collect();
            if values[..5].iter().all(|&v| v == values[0]) {
                adaptive.extend([128 + 5, values[0], 4]);
                adaptive.extend(&values[5..]);
            } else {
                adaptive.push(9);
                adaptive.extend(&values);
            }
        }
    }
    [flat, old, adaptive]
}

/// All three storage forms decode to the same pixels, each `(c + 0.5) · 2^(e − 136)`:
/// (128, 64, 0, 129) is (1.00390625, 0.50390625, 0.00390625) exactly, e = 0 is black.
/// Seen failing with the exponent bias 128 + 7 (every value doubled), and with the
/// adaptive form's run counts taken as `count − 127`.
#[test]
fn rgbe_storage_forms_decode_to_known_values() {
    let expected: Vec<[f32; 3]> = rgbe_pixels().into_iter().map(rgbe_to_float).collect();
    assert_eq!(expected[0], [1.003_906_25, 0.503_906_25, 0.003_906_25]);
    assert_eq!(expected[5], [255.5, 255.5, 255.5]);
    assert_eq!(expected[7], [0.0; 3]);
    for (form, bytes) in ["flat", "old run-length", "adaptive run-length"].iter().zip(rgbe_files()) {
        let image = decode_rgbe(&bytes).unwrap_or_else(|e| panic!("{form}: {e}"));
        assert_eq!((image.width, image.height), (9, 2), "{form}");
        assert_eq!(image.pixels, expected, "{form}");
    }
}

/// Every truncation of every form is an error (the header, a scanline's head, a run), and
/// so are a run past the line, a width mismatch in a run-length header, another
/// orientation and another pixel format.
#[test]
fn damaged_rgbe_files_are_errors() {
    for bytes in rgbe_files() {
        for n in 0..bytes.len() {
            assert!(decode_rgbe(&bytes[..n]).is_err(), "truncated to {n} of {} bytes", bytes.len());
        }
    }
    let [_, _, adaptive] = rgbe_files();
    let head = rgbe_header(9, 2).len();
    let mut long_run = adaptive.clone();
    long_run[head + 4] = 128 + 10;
    assert!(decode_rgbe(&long_run).unwrap_err().contains("past the end of the line"));
    let mut wrong_width = adaptive.clone();
    wrong_width[head + 3] = 8;
    assert!(decode_rgbe(&wrong_width).unwrap_err().contains("says 8 pixels wide"));
    let flipped = String::from_utf8_lossy(&rgbe_header(9, 2)).replace("-Y 2 +X 9", "+Y 2 +X 9");
    assert!(decode_rgbe(flipped.as_bytes()).unwrap_err().contains("supported: -Y height +X width"));
    let xyz = String::from_utf8_lossy(&rgbe_header(9, 2)).replace("32-bit_rle_rgbe", "32-bit_rle_xyze");
    assert!(decode_rgbe(xyz.as_bytes()).unwrap_err().contains("32-bit_rle_xyze"));
    assert!(decode_rgbe(b"P6\n1 1\n255\n").unwrap_err().contains("not a Radiance"));
}

/// PFM in both byte orders and both channel counts; the file's first row is the image's
/// bottom. Seen failing with the rows read top to bottom (the `.rev()` removed), and with
/// the byte order taken from a positive scale as little-endian.
#[test]
fn pfm_orders_channels_and_rows() {
    // 2 × 2, stored bottom row first: bottom (1, 2, 3) (4, 5, 6), top (7, 8, 9) (-1.5, 0, 1e30).
    let values: [f32; 12] = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, -1.5, 0.0, 1e30];
    let top_down = vec![[7.0, 8.0, 9.0], [-1.5, 0.0, 1e30], [1.0, 2.0, 3.0], [4.0, 5.0, 6.0]];
    for (scale, little) in [("-1.0", true), ("1.0", false), ("-0.003", true)] {
        let mut bytes = format!("PF\n2 2\n{scale}\n").into_bytes();
        for v in values {
            bytes.extend(if little { v.to_le_bytes() } else { v.to_be_bytes() });
        }
        let image = decode_pfm(&bytes).unwrap_or_else(|e| panic!("scale {scale}: {e}"));
        assert_eq!((image.width, image.height), (2, 2));
        assert_eq!(image.pixels, top_down, "scale {scale}");
        for n in 0..bytes.len() {
            assert!(decode_pfm(&bytes[..n]).is_err(), "truncated to {n} bytes");
        }
        let mut extra = bytes.clone();
        extra.push(0);
        assert!(decode_pfm(&extra).unwrap_err().contains("need 48 bytes"));
    }
    // Grey, 3 × 1, one space between the fields.
    let mut grey = b"Pf 3 1 -1 ".to_vec();
    [0.25f32, 0.5, 2.0].iter().for_each(|v| grey.extend(v.to_le_bytes()));
    let image = decode_pfm(&grey).unwrap();
    assert_eq!(image.pixels, vec![[0.25; 3], [0.5; 3], [2.0; 3]]);
    assert!(decode_pfm(b"PF\n2 2\n0\n").unwrap_err().contains("non-zero"));
    assert!(decode_pfm(b"P6\n2 2\n255\n").unwrap_err().contains("not a PFM"));
}

/// A header declaring 100000 × 100000 pixels (or 2^26 + 1 within the side limit) is
/// refused from the header, before any pixel buffer; a legal size with too little data
/// is refused when the data runs out (RGBE) or before decoding (PFM). Seen failing (an
/// allocation of 120 GB, the test aborted) with `check_dimensions` removed from
/// `decode_pfm` and the data-size check after the buffer.
#[test]
fn hostile_headers_are_refused_before_allocating() {
    let huge = b"#?RADIANCE\n\n-Y 100000 +X 100000\n";
    assert!(decode_rgbe(huge).unwrap_err().contains("100000x100000 pixels"));
    assert!(decode_pfm(b"PF\n100000 100000\n-1\n").unwrap_err().contains("100000x100000 pixels"));
    assert!(decode_pfm(b"PF\n32768 2049\n-1\n").unwrap_err().contains("at most 67108864"));
    let mut short = b"#?RADIANCE\n\n-Y 2048 +X 32768\n".to_vec();
    short.extend([2, 2, 0x80, 0]);
    assert!(decode_rgbe(&short).unwrap_err().contains("scanline 0 of 2048"));
    assert!(decode_pfm(b"PF\n8192 8192\n-1\n\0\0\0\0").unwrap_err().contains("the file holds 4"));
    assert!(decode_pfm(b"PF\n0 1\n-1\n").is_err() && decode_rgbe(b"#?RGBE\n\n-Y 0 +X 4\n").is_err());
}
