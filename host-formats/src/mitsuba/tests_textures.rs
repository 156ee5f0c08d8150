//! Textures in the reader: what a material reads at a hit, texture coordinates from
//! every shape as Mitsuba defines them, and bad texture input named by file and line.

use ember_core::bsdf::TransportMode;
use ember_core::math::{Vec2, Vec3};
use ember_core::scene::cube_texcoords;
use ember_core::spectrum::Rgb;

use super::tests::{build, load_body, temp_dir};
use super::{LoadOptions, load_scene};

/// The diffuse albedo material `id` has at `uv` (f·π at normal incidence).
fn albedo(scene: &ember_core::scene::Scene, id: u32, uv: Vec2) -> Rgb {
    let m = scene.material(id, uv);
    m.eval(Vec3::Z, Vec3::Z, TransportMode::Radiance) * core::f32::consts::PI
}

/// A 2 × 1 PNG (8-bit RGB) with texels `a` and `b`.
fn write_png(path: &std::path::Path, a: [u8; 3], b: [u8; 3]) {
    let file = std::fs::File::create(path).unwrap();
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), 2, 1);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().unwrap();
    w.write_image_data(&[a, b].concat()).unwrap();
}

/// An 8-bit sRGB PNG is decoded to linear per texel (128 → 0.2158) and filtered between
/// texel centres; `raw` skips the decoding; a checkerboard's `to_uv` scales its squares.
/// Removing the sRGB decoding makes the first check read 0.502.
#[test]
fn bitmap_and_checkerboard_values() {
    let dir = temp_dir("tex_values");
    write_png(&dir.join("t.png"), [128, 0, 255], [0, 0, 0]);
    let body = r#"<shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="t.png"/><string name="wrap_mode" value="clamp"/></texture></bsdf></shape>
<shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="t.png"/><boolean name="raw" value="true"/></texture></bsdf></shape>
<shape type="rectangle"><bsdf type="plastic"><texture type="checkerboard" name="diffuse_reflectance"><rgb name="color0" value="1, 0, 0"/><rgb name="color1" value="0, 0, 1"/><transform name="to_uv"><scale x="4" y="4"/></transform></texture></bsdf></shape>"#;
    let (scene, _) = build(load_body(&dir, body, &LoadOptions::default()).unwrap());
    let a = albedo(&scene, 0, Vec2::new(0.25, 0.5));
    assert!((a.r - 0.21586).abs() < 1e-4 && a.g == 0.0 && (a.b - 1.0).abs() < 1e-5, "{a:?}");
    let mid = albedo(&scene, 0, Vec2::new(0.5, 0.5));
    assert!((mid.r - 0.5 * 0.21586).abs() < 1e-4, "{mid:?}");
    let raw = albedo(&scene, 1, Vec2::new(0.25, 0.5));
    assert!((raw.r - 128.0 / 255.0).abs() < 1e-5, "{raw:?}");
    // Checkerboard squares of 1/8 in uv: (0.05, 0.05) is color0, (0.2, 0.05) color1.
    let red = scene.material(2, Vec2::new(0.05, 0.05)).eval(Vec3::Z, Vec3::Z, TransportMode::Radiance);
    let blue = scene.material(2, Vec2::new(0.2, 0.05)).eval(Vec3::Z, Vec3::Z, TransportMode::Radiance);
    assert!(red.r > 0.0 && red.b == 0.0 && blue.b > 0.0 && blue.r == 0.0, "{red:?} {blue:?}");
}

/// Cube faces map onto [0, 1]² as Mitsuba's `cube.cpp` tabulates them (its 24 corners and
/// texture coordinates, transcribed), and OBJ texture coordinates are flipped in v.
#[test]
fn texture_coordinates_follow_mitsuba() {
    #[rustfmt::skip]
    let corners: [([f32; 3], [f32; 2]); 24] = [
        ([1., -1., -1.], [0., 1.]), ([1., -1., 1.], [1., 1.]), ([-1., -1., 1.], [1., 0.]), ([-1., -1., -1.], [0., 0.]),
        ([1., 1., -1.], [0., 1.]), ([-1., 1., -1.], [1., 1.]), ([-1., 1., 1.], [1., 0.]), ([1., 1., 1.], [0., 0.]),
        ([1., -1., -1.], [0., 1.]), ([1., 1., -1.], [1., 1.]), ([1., 1., 1.], [1., 0.]), ([1., -1., 1.], [0., 0.]),
        ([1., -1., 1.], [0., 1.]), ([1., 1., 1.], [1., 1.]), ([-1., 1., 1.], [1., 0.]), ([-1., -1., 1.], [0., 0.]),
        ([-1., -1., 1.], [0., 1.]), ([-1., 1., 1.], [1., 1.]), ([-1., 1., -1.], [1., 0.]), ([-1., -1., -1.], [0., 0.]),
        ([1., 1., -1.], [0., 1.]), ([1., -1., -1.], [1., 1.]), ([-1., -1., -1.], [1., 0.]), ([-1., 1., -1.], [0., 0.]),
    ];
    let normals = [Vec3::NEG_Y, Vec3::Y, Vec3::X, Vec3::Z, Vec3::NEG_X, Vec3::NEG_Z];
    for (i, (p, uv)) in corners.iter().enumerate() {
        let got = cube_texcoords(Vec3::from_array(*p), normals[i / 4]);
        assert_eq!(got, Vec2::from_array(*uv), "corner {i}");
    }
    let dir = temp_dir("tex_obj");
    std::fs::write(dir.join("m.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.25 0.1\nvt 0.5 0.2\nvt 0.75 0.3\nf 1/1 2/2 3/3\n").unwrap();
    let body = r#"<shape type="obj"><string name="filename" value="m.obj"/></shape>"#;
    let (_, geometry) = build(load_body(&dir, body, &LoadOptions::default()).unwrap());
    let t = &geometry.triangles[0];
    assert_eq!(t.uv.map(|uv| uv.map(|v| (v * 100.0).round())), Some([Vec2::new(25.0, 90.0), Vec2::new(50.0, 80.0), Vec2::new(75.0, 70.0)]));
    assert_eq!(t.texcoords(0.0, 1.0), t.uv.unwrap()[2]);
}

/// CRC-32 (IEEE, reflected), as PNG chunks carry it.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 { 0xedb8_8320 ^ (c >> 1) } else { c >> 1 };
        }
    }
    !c
}

/// A PNG of `w` × `h` 8-bit RGB texels whose IDAT holds an empty zlib stream: a valid
/// header for any size, without the data.
fn huge_png_header(w: u32, h: u32) -> Vec<u8> {
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut chunk = |kind: &[u8], data: &[u8]| {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let body = [kind, data].concat();
        out.extend_from_slice(&body);
        out.extend_from_slice(&crc32(&body).to_be_bytes());
    };
    chunk(b"IHDR", &[&w.to_be_bytes()[..], &h.to_be_bytes(), &[8, 2, 0, 0, 0]].concat());
    chunk(b"IDAT", &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01]);
    chunk(b"IEND", &[]);
    out
}

/// Bad texture input: each error names the file (or the parameter) and the problem.
#[test]
fn texture_errors_name_the_file() {
    let dir = temp_dir("tex_errors");
    std::fs::write(dir.join("bad.png"), b"\x89PNG\r\n\x1a\n garbage").unwrap();
    std::fs::write(dir.join("t.jpg"), b"\xff\xd8\xff").unwrap();
    std::fs::write(dir.join("t.tga"), b"\0\0\x02").unwrap();
    write_png(&dir.join("ok.png"), [1, 2, 3], [4, 5, 6]);
    // A PNG declaring 20 000 × 20 000 texels with a token of data: refused from its header,
    // before anything that size is allocated.
    std::fs::write(dir.join("huge.png"), huge_png_header(20_000, 20_000)).unwrap();
    let tex = |inner: &str| format!(r#"<shape type="rectangle"><bsdf type="diffuse">{inner}</bsdf></shape>"#);
    let cases = [
        (tex(r#"<texture type="bitmap" name="reflectance"><string name="filename" value="missing.png"/></texture>"#), vec!["missing.png", "cannot open"]),
        (tex(r#"<texture type="bitmap" name="reflectance"><string name="filename" value="bad.png"/></texture>"#), vec!["bad.png", "PNG"]),
        (tex(r#"<texture type="bitmap" name="reflectance"><string name="filename" value="t.jpg"/></texture>"#), vec!["t.jpg", "not a readable JPEG"]),
        (tex(r#"<texture type="bitmap" name="reflectance"><string name="filename" value="t.tga"/></texture>"#), vec!["t.tga", "unsupported image format"]),
        (tex(r#"<texture type="bitmap" name="reflectance"/>"#), vec!["needs a `filename`"]),
        (tex(r#"<texture type="bitmap" name="reflectance"><string name="filename" value="huge.png"/></texture>"#), vec!["huge.png", "20000x20000"]),
        (
            tex(r#"<texture type="bitmap" name="reflectance"><string name="filename" value="ok.png"/><string name="wrap_mode" value="tile"/></texture>"#),
            vec!["wrap_mode \"tile\""],
        ),
        (tex(r#"<texture type="checkerboard" name="roughness"/>"#), vec!["no textured parameter `roughness`"]),
        (tex(r#"<texture type="checkerboard"/>"#), vec!["needs a `name`"]),
        (tex(r#"<rgb name="reflectance" value="0.5"/><texture type="checkerboard" name="reflectance"/>"#), vec!["given both as a value"]),
    ];
    for (i, (body, needles)) in cases.iter().enumerate() {
        let Err(e) = load_body(&dir, body, &LoadOptions::default()) else { panic!("case {i} loaded") };
        let msg = e.to_string();
        assert!(msg.contains("scene.xml:"), "case {i}: {msg}");
        for n in needles {
            assert!(msg.contains(n), "case {i}: `{n}` missing from {msg}");
        }
    }
    // A texture declared at the top and shared by reference is built once.
    let body = r#"<texture type="bitmap" id="t"><string name="filename" value="ok.png"/></texture>
<shape type="rectangle"><bsdf type="diffuse"><ref name="reflectance" id="t"/></bsdf></shape>
<shape type="cube"><bsdf type="plastic"><ref name="diffuse_reflectance" id="t"/></bsdf></shape>"#;
    let loaded = load_body(&dir, body, &LoadOptions::default()).unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let (scene, _) = build(loaded);
    assert_eq!(scene.textures.len(), 1);
    let _ = load_scene;
}
