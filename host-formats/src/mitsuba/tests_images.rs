//! Image formats in the reader beyond PNG and EXR (issue 56): JPEG (grey and colour,
//! baseline and progressive), Radiance RGBE and PFM as bitmaps and environment maps.
//! The JPEGs are encoded here by a dev-dependency encoder; the float files are written
//! byte by byte.

use ember_core::bsdf::TransportMode;
use ember_core::math::{Vec2, Vec3};
use ember_core::spectrum::Rgb;
use ember_core::texture::srgb_to_linear;
use jpeg_encoder::{ColorType, Encoder, SamplingFactor};

use super::LoadOptions;
use super::images::decode_jpeg;
use super::tests::{build, load_body, temp_dir};

/// A 16 × 16 image of four flat 8 × 8 quadrants (so every JPEG block is flat and
/// survives quality 100 within a step or two), top-left, top-right, bottom-left,
/// bottom-right.
const QUADRANTS: [[u8; 3]; 4] = [[200, 30, 90], [10, 250, 128], [0, 0, 0], [255, 255, 255]];

fn quadrant_pixels(grey: bool) -> Vec<u8> {
    let mut out = Vec::new();
    for y in 0..16 {
        for x in 0..16 {
            let q = QUADRANTS[(y / 8) * 2 + x / 8];
            if grey { out.push(q[1]) } else { out.extend(q) }
        }
    }
    out
}

/// The quadrant image as a JPEG: colour (4:4:4) or grey, baseline or progressive.
fn quadrant_jpeg(grey: bool, progressive: bool) -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut encoder = Encoder::new(&mut bytes, 100);
    encoder.set_sampling_factor(SamplingFactor::R_4_4_4);
    encoder.set_progressive(progressive);
    let color = if grey { ColorType::Luma } else { ColorType::Rgb };
    encoder.encode(&quadrant_pixels(grey), 16, 16, color).unwrap();
    bytes
}

/// Each of the four kinds decodes to the quadrants within 2/255 (raw), grey as three equal
/// channels, and without `raw` each value is the sRGB table's value of the same byte.
/// Seen failing with the table built raw for both (no sRGB decoding): 200 → 0.784 read,
/// 0.578 expected.
#[test]
fn jpeg_kinds_decode_to_known_pixels() {
    for grey in [false, true] {
        for progressive in [false, true] {
            let what = format!("grey {grey}, progressive {progressive}");
            let bytes = quadrant_jpeg(grey, progressive);
            let (w, h, raw) = decode_jpeg(&bytes, true).unwrap_or_else(|e| panic!("{what}: {e}"));
            let (_, _, srgb) = decode_jpeg(&bytes, false).unwrap();
            assert_eq!((w, h, raw.len()), (16, 16, 256), "{what}");
            for (i, (&r, &s)) in raw.iter().zip(&srgb).enumerate() {
                let q = QUADRANTS[(i / 16 / 8) * 2 + (i % 16) / 8];
                let want = if grey { [q[1]; 3] } else { q };
                for (c, (got, lin)) in [(r.r, s.r), (r.g, s.g), (r.b, s.b)].into_iter().enumerate() {
                    assert!((got - want[c] as f32 / 255.0).abs() <= 2.0 / 255.0, "{what}: pixel {i} channel {c}: {got} for {}", want[c]);
                    let byte = (got * 255.0).round() as u8;
                    assert_eq!(lin, srgb_to_linear(byte), "{what}: pixel {i} channel {c}");
                }
            }
        }
    }
}

/// Every truncation of a baseline and a progressive JPEG is an error, never a panic nor
/// a partly grey image (the decoder's lenient mode fills missing blocks, and even its
/// strict mode pads a scan cut short with zero bits, so the reader also requires the
/// end-of-image marker after the last scan). Seen failing with that marker check
/// removed: the baseline file cut to 649 of its 652 bytes decoded.
#[test]
fn truncated_jpegs_are_errors() {
    for progressive in [false, true] {
        let bytes = quadrant_jpeg(false, progressive);
        for n in 0..bytes.len() {
            assert!(decode_jpeg(&bytes[..n], false).is_err(), "progressive {progressive}: truncated to {n} of {} bytes", bytes.len());
        }
    }
}

/// The frame header's size is checked before decoding: 65535 × 65535 is over the side
/// limit, and 8192 × 8192 (within it) cannot come from a file of a few hundred bytes.
/// Seen failing with the expansion bound removed: the test then ran for minutes with the
/// process at 6.6 GB, and was killed.
#[test]
fn hostile_jpeg_headers_are_refused_before_decoding() {
    let bytes = quadrant_jpeg(false, false);
    let sof = bytes.windows(2).position(|w| w == [0xff, 0xc0]).expect("a baseline frame header");
    let with_size = |side: u16| {
        let mut b = bytes.clone();
        b[sof + 5..sof + 7].copy_from_slice(&side.to_be_bytes());
        b[sof + 7..sof + 9].copy_from_slice(&side.to_be_bytes());
        b
    };
    let e = decode_jpeg(&with_size(65535), false).unwrap_err();
    assert!(e.contains("65535"), "{e}");
    let e = decode_jpeg(&with_size(8192), false).unwrap_err();
    assert!(e.contains("8192x8192 pixels cannot be stored"), "{e}");
}

/// A frame with a component sampled 2 × 3 is refused before decoding: zune-jpeg panicked
/// on it (the fuzz target's find, `fuzz/seeds/image_readers/jpeg_sampling_2x3`). The
/// real files still decode, and an APP segment holding a whole second JPEG (a thumbnail)
/// is no second frame. Seen failing with the component bytes read one byte early (the
/// check then missed the factor, and the decoder panicked).
#[test]
fn unsupported_sampling_factors_are_refused() {
    let seed = include_bytes!("../../../fuzz/seeds/image_readers/jpeg_sampling_2x3");
    let e = decode_jpeg(&seed[1..], false).unwrap_err();
    assert!(e.contains("sampled 2x3 against the first's 1x1"), "{e}");
    for (grey, progressive) in [(false, false), (true, true), (false, true)] {
        let bytes = quadrant_jpeg(grey, progressive);
        assert!(decode_jpeg(&bytes, false).is_ok());
        // The same file with the whole JPEG again inside an APP1 segment after SOI.
        let inner = quadrant_jpeg(true, false);
        let mut with_thumbnail = vec![0xff, 0xd8, 0xff, 0xe1];
        with_thumbnail.extend_from_slice(&((inner.len() + 2) as u16).to_be_bytes());
        with_thumbnail.extend_from_slice(&inner);
        with_thumbnail.extend_from_slice(&bytes[2..]);
        let (w, h, _) = decode_jpeg(&with_thumbnail, false).unwrap_or_else(|e| panic!("grey {grey}, progressive {progressive}: {e}"));
        assert_eq!((w, h), (16, 16));
    }
}

/// The diffuse albedo of material `id` at `uv` (f·π at normal incidence).
fn albedo(scene: &ember_core::scene::Scene, id: u32, uv: Vec2) -> Rgb {
    scene.material(id, uv).eval(Vec3::Z, Vec3::Z, TransportMode::Radiance) * core::f32::consts::PI
}

/// JPEG, RGBE and PFM bitmaps in a scene, and RGBE and PFM environment maps: the texel at
/// the top-left quadrant (v = 0 is the image's top row, as for PNG) reads as decoded;
/// the float formats are linear whatever `raw` says. Seen failing with PFM's rows
/// not turned over (the bottom row's 0.75 read at the top).
#[test]
fn new_formats_load_as_bitmaps_and_envmaps() {
    let dir = temp_dir("new_formats");
    std::fs::write(dir.join("q.jpg"), quadrant_jpeg(false, true)).unwrap();
    // RGBE, 1 × 2 flat: top (128, 64, 0, 129), bottom black.
    let mut hdr = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 1\n".to_vec();
    hdr.extend([128, 64, 0, 129, 0, 0, 0, 0]);
    std::fs::write(dir.join("t.hdr"), &hdr).unwrap();
    // PFM, 1 × 2 grey, little-endian: stored bottom (0.75) then top (0.25).
    let mut pfm = b"Pf\n1 2\n-1.0\n".to_vec();
    [0.75f32, 0.25].iter().for_each(|v| pfm.extend(v.to_le_bytes()));
    std::fs::write(dir.join("t.pfm"), &pfm).unwrap();
    let bitmap = |file: &str| {
        format!(
            r#"<shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="{file}"/><string name="filter_type" value="nearest"/></texture></bsdf></shape>"#
        )
    };
    let body = [bitmap("q.jpg"), bitmap("t.hdr"), bitmap("t.pfm")].concat();
    let (scene, _) = build(load_body(&dir, &body, &LoadOptions::default()).unwrap());
    let top = Vec2::new(0.25, 0.25);
    let jpg = albedo(&scene, 0, top);
    assert!((jpg.r - srgb_to_linear(200)).abs() < 0.02 && (jpg.g - srgb_to_linear(30)).abs() < 0.01, "{jpg:?}");
    let rgbe = albedo(&scene, 1, top);
    assert!((rgbe.r - 1.003_906_25).abs() < 1e-5 && (rgbe.g - 0.503_906_25).abs() < 1e-5, "{rgbe:?}");
    assert_eq!(albedo(&scene, 1, Vec2::new(0.5, 0.75)), Rgb::splat(0.0));
    let grey = albedo(&scene, 2, top);
    assert!((grey.r - 0.25).abs() < 1e-6 && grey.g == grey.r, "{grey:?}");

    for file in ["t.hdr", "t.pfm"] {
        let body = format!(r#"<emitter type="envmap"><string name="filename" value="{file}"/></emitter>"#);
        let loaded = load_body(&dir, &body, &LoadOptions::default()).unwrap_or_else(|e| panic!("{file}: {e}"));
        let _ = build(loaded);
    }
}
