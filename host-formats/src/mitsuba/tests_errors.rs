//! Every rejected construct gives `file:line:col: message` naming what is supported.
//! The scenes below start their own content on line 4 (after `<scene>` and the two
//! lines of [`SENSOR`]).

use std::path::Path;

use super::tests::{SENSOR, suite_dir, temp_dir};
use super::{LoadOptions, SceneFileError, load_scene};

/// Write `<scene>` + sensor + `content` and load it, expecting an error.
pub(super) fn fail(test: &str, content: &str) -> SceneFileError {
    fail_with(test, content, &[], &LoadOptions::default())
}

/// Like [`fail`], with extra files written into the scene's directory first.
fn fail_with(test: &str, content: &str, files: &[(&str, &[u8])], options: &LoadOptions) -> SceneFileError {
    let dir = temp_dir(test);
    for (name, data) in files {
        std::fs::write(dir.join(name), data).unwrap();
    }
    let path = dir.join("scene.xml");
    std::fs::write(&path, format!("<scene version=\"3.0.0\">\n{SENSOR}\n{content}\n</scene>\n")).unwrap();
    match load_scene(&path, options) {
        Ok(_) => panic!("{test}: the scene loaded"),
        Err(e) => e,
    }
}

/// 1-based column of `at` in the `n`th line (1-based) of `content`, which starts on
/// line 4 of the file.
pub(super) fn col(content: &str, line: u32, at: &str) -> u32 {
    let text = content.lines().nth(line as usize - 4).expect("line exists");
    text.find(at).map(|i| i as u32 + 1).unwrap_or_else(|| panic!("`{at}` not in `{text}`"))
}

/// The error is at `line:col` of its file and its text contains every needle.
#[track_caller]
pub(super) fn check(e: &SceneFileError, line: u32, col: u32, needles: &[&str]) {
    let text = e.to_string();
    assert!(text.starts_with(&format!("{}:{line}:{col}: ", e.file.display())), "wrong position: {text}");
    assert!(e.file.ends_with("scene.xml"), "{text}");
    for n in needles {
        assert!(text.contains(n), "`{n}` missing from: {text}");
    }
}

#[test]
fn unknown_plugins_name_the_supported_ones() {
    let c = "  <shape type=\"torus\"/>";
    let e = fail("plugin_shape", c);
    check(&e, 4, col(c, 4, "<shape"), &["unsupported shape type \"torus\"", "obj, ply, rectangle, cube, sphere, disk"]);
    let c = "<shape type=\"cube\">\n   <bsdf type=\"hair\"/></shape>";
    let e = fail("plugin_bsdf", c);
    check(&e, 5, col(c, 5, "<bsdf"), &["unsupported bsdf type \"hair\"", "roughdielectric, plastic, roughplastic, principled, twosided"]);
    let c = "<shape type=\"cube\"><bsdf type=\"diffuse\">\n   <texture type=\"noise\" name=\"reflectance\"/></bsdf></shape>";
    let e = fail("plugin_texture", c);
    check(&e, 5, col(c, 5, "<texture"), &["unsupported texture type \"noise\"", "bitmap, checkerboard"]);
    let c = "<emitter type=\"hdrsky\"/>";
    let e = fail("plugin_emitter", c);
    check(&e, 4, col(c, 4, "<emitter"), &["unsupported emitter type \"hdrsky\"", "point, spot, directional, constant, envmap"]);
    // A lanczos reconstruction filter is rejected (box, tent and gaussian are read).
    let dir = temp_dir("plugin_rfilter2");
    let path = dir.join("scene.xml");
    std::fs::write(&path, "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" value=\"30\"/>\n<film type=\"hdrfilm\">\n  <rfilter type=\"lanczos\"/></film></sensor></scene>").unwrap();
    check(&load_scene(&path, &LoadOptions::default()).unwrap_err(), 4, 3, &["unsupported rfilter type \"lanczos\"", "box, tent, gaussian"]);
    // Bad filter and lens values name their line.
    let bad = [
        (
            "rfilter_neg",
            "<rfilter type=\"gaussian\">\n  <float name=\"stddev\" value=\"-0.5\"/></rfilter>",
            "perspective",
            "",
            4,
            "gaussian `stddev` must be finite and positive",
        ),
        ("rfilter_nan", "<rfilter type=\"tent\">\n  <float name=\"radius\" value=\"nan\"/></rfilter>", "perspective", "", 4, "number \"nan\" is not finite"),
        ("lens_neg", "", "thinlens", "\n  <float name=\"aperture_radius\" value=\"-1\"/>", 3, "`aperture_radius` must be finite and non-negative"),
        (
            "lens_focus",
            "",
            "thinlens",
            "<float name=\"aperture_radius\" value=\"0.1\"/>\n  <float name=\"focus_distance\" value=\"0\"/>",
            3,
            "`focus_distance` must be finite and positive",
        ),
    ];
    for (name, rfilter, sensor, lens, line, msg) in bad {
        let dir = temp_dir(name);
        let path = dir.join("scene.xml");
        let xml = format!(
            "<scene version=\"3.0.0\">\n<sensor type=\"{sensor}\"><float name=\"fov\" value=\"30\"/>{lens}\n<film type=\"hdrfilm\">{rfilter}</film></sensor></scene>"
        );
        std::fs::write(&path, xml).unwrap();
        let e = load_scene(&path, &LoadOptions::default()).unwrap_err();
        let text = e.to_string();
        assert!(text.contains(msg) && text.contains(&format!("scene.xml:{line}:")), "{name}: {text}");
    }
}

#[test]
fn unreferenced_properties_are_errors() {
    let c = "<shape type=\"cube\"><bsdf type=\"diffuse\">\n\t<float name=\"roughness\" value=\"0.5\"/></bsdf></shape>";
    let e = fail("unref", c);
    check(&e, 5, col(c, 5, "<float"), &["unreferenced property `roughness`", "<bsdf type=\"diffuse\">", "accepts: reflectance"]);
    let c = "<shape type=\"sphere\">\n<float name=\"radius\" value=\"1\"/>\n<float name=\"near_clip\" value=\"1\"/></shape>";
    let e = fail("unref_shape", c);
    check(&e, 6, col(c, 6, "<float"), &["unreferenced property `near_clip`", "to_world, flip_normals, center, radius"]);
    let c = "<shape type=\"sphere\">\n<float name=\"radius\" value=\"1\"/>\n<float name=\"radius\" value=\"2\"/></shape>";
    let e = fail("unref_dup", c);
    check(&e, 6, col(c, 6, "<float"), &["property `radius` is given twice", "first at line 5"]);
}

#[test]
fn missing_and_broken_mesh_files_are_errors() {
    let c = "<shape type=\"obj\">\n  <string name=\"filename\" value=\"nothere.obj\"/></shape>";
    let e = fail("missing", c);
    check(&e, 5, col(c, 5, "<string"), &["cannot load the obj mesh", "nothere.obj"]);
    let nan = b"v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n";
    let e = fail_with("nan", "<shape type=\"obj\">\n <string name=\"filename\" value=\"nan.obj\"/></shape>", &[("nan.obj", nan)], &LoadOptions::default());
    check(&e, 5, 2, &["nan.obj", "vertex 2 is not finite"]);
    let ply = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\x00\x00";
    let e = fail_with("ply", "<shape type=\"ply\">\n <string name=\"filename\" value=\"t.ply\"/></shape>", &[("t.ply", ply)], &LoadOptions::default());
    check(&e, 5, 2, &["cannot load the ply mesh", "unexpected end of data"]);
    let bad_index = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 x\n3 0 1 2\n";
    let e =
        fail_with("ply_ascii", "<shape type=\"ply\">\n <string name=\"filename\" value=\"t.ply\"/></shape>", &[("t.ply", bad_index)], &LoadOptions::default());
    check(&e, 5, 2, &["line 12: malformed number \"x\""]);
}

#[test]
fn malformed_values_point_at_the_value() {
    let c = "<shape type=\"sphere\">\n  <float name=\"radius\" value=\"1.2.3\"/></shape>";
    let e = fail("number", c);
    check(&e, 5, col(c, 5, "1.2.3"), &["malformed number \"1.2.3\""]);
    let c = "<integrator type=\"path\"><integer name=\"max_depth\" value=\"2.5\"/></integrator>";
    let e = fail("integer", c);
    check(&e, 4, col(c, 4, "2.5"), &["malformed integer \"2.5\""]);
    let c = "<shape type=\"sphere\"><float name=\"radius\" value=\"1e39\"/></shape>";
    let e = fail("infinite", c);
    check(&e, 4, col(c, 4, "1e39"), &["not finite"]);
    let c = "<shape type=\"cube\"><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"1 2\"/></bsdf></shape>";
    let e = fail("rgb", c);
    check(&e, 4, col(c, 4, "1 2"), &["<rgb> needs 1 or 3 values"]);
    let c = "<shape type=\"cube\"><boolean name=\"flip_normals\" value=\"yes\"/></shape>";
    let e = fail("bool", c);
    check(&e, 4, col(c, 4, "yes"), &["malformed boolean \"yes\""]);
    let c = "<shape type=\"cube\"><transform name=\"to_world\"><matrix value=\"1 2 3\"/></transform></shape>";
    let e = fail("matrix", c);
    check(&e, 4, col(c, 4, "1 2 3"), &["<matrix> needs 16 values"]);
}

#[test]
fn broken_references_and_wrong_tags_are_errors() {
    let c = "<shape type=\"cube\">\n    <ref id=\"nope\"/></shape>";
    let e = fail("ref", c);
    check(&e, 5, col(c, 5, "nope"), &["unknown id \"nope\""]);
    let c = "<shape type=\"cube\" id=\"a\"/>\n<shape type=\"cube\"><ref id=\"a\"/></shape>";
    let e = fail("ref_kind", c);
    check(&e, 5, col(c, 5, "<ref"), &["<shape type=\"cube\"> cannot contain <shape type=\"cube\">", "<bsdf>, <emitter>"]);
    let c = "<shape type=\"sphere\">\n<rgb name=\"radius\" value=\"1\"/></shape>";
    let e = fail("wrong_value_tag", c);
    check(&e, 5, col(c, 5, "<rgb"), &["property `radius` of <shape type=\"sphere\"> must be a <float>, not <rgb>"]);
    let c = "<shape type=\"cube\">\n  <texture type=\"bitmap\"/></shape>";
    let e = fail("wrong_element", c);
    check(&e, 5, col(c, 5, "<texture"), &["<shape type=\"cube\"> cannot contain <texture type=\"bitmap\">", "<bsdf>, <emitter>"]);
    let c = "<shape type=\"cube\">\n  <foo/></shape>";
    let e = fail("unknown_element", c);
    check(&e, 5, col(c, 5, "<foo"), &["unsupported element <foo>", "float, integer"]);
    let c = "<include filename=\"x.xml\"/>";
    let e = fail("scene_element", c);
    check(&e, 4, col(c, 4, "<include"), &["unsupported element <include>", "<scene> accepts"]);
    // An integer property given as a float (this scene has its own sensor).
    let dir = temp_dir("int_for_float");
    let path = dir.join("scene.xml");
    let c = "<film type=\"hdrfilm\"><float name=\"width\" value=\"3\"/></film>";
    std::fs::write(&path, format!("<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" value=\"1\"/>\n\n{c}</sensor></scene>"))
        .unwrap();
    let e = load_scene(&path, &LoadOptions::default()).unwrap_err();
    check(&e, 4, col(c, 4, "<float"), &["must be an <integer>, not <float>"]);
    let c = "<shape type=\"cube\" kind=\"x\"/>";
    let e = fail("attr", c);
    check(&e, 4, col(c, 4, "kind="), &["unexpected attribute `kind`", "type, id, name"]);
    let c = "<bsdf type=\"diffuse\" id=\"a\"/>\n<bsdf type=\"diffuse\" id=\"a\"/>";
    let e = fail("dup_id", c);
    check(&e, 5, col(c, 5, "a\"/>"), &["id \"a\" is already used at line 4"]);
    let c = "<emitter type=\"area\"/>";
    let e = fail("area_top", c);
    check(&e, 4, col(c, 4, "<emitter"), &["must be nested in the <shape>"]);
    let c = "<shape type=\"cube\"><emitter type=\"point\"/></shape>";
    let e = fail("point_in_shape", c);
    check(&e, 4, col(c, 4, "<emitter"), &["only `area` emitters can be nested"]);
    let c = "<shape type=\"cube\"><bsdf type=\"twosided\"><bsdf type=\"dielectric\"/></bsdf></shape>";
    let e = fail("twosided_glass", c);
    check(&e, 4, col(c, 4, "<bsdf"), &["cannot wrap a BSDF that transmits"]);
    let c = "<shape type=\"cube\"><bsdf type=\"diffuse\"/>\n<bsdf type=\"diffuse\"/></shape>";
    let e = fail("two_bsdfs", c);
    check(&e, 5, col(c, 5, "<bsdf"), &["takes at most one <bsdf>"]);
    let c = "<shape type=\"sphere\"><transform name=\"to_world\"><scale x=\"2\"/></transform></shape>";
    let e = fail("ellipsoid", c);
    check(&e, 4, col(c, 4, "<shape"), &["ellipsoids are not supported"]);
    let c = "<shape type=\"cube\"><bsdf type=\"conductor\"><string name=\"material\" value=\"Pt\"/></bsdf></shape>";
    let e = fail("conductor", c);
    check(&e, 4, col(c, 4, "<string"), &["unknown conductor material \"Pt\"", "Al, Cu, Au, Ag"]);
    let c = "<shape type=\"cube\"><bsdf type=\"roughconductor\"><string name=\"distribution\" value=\"phong\"/></bsdf></shape>";
    let e = fail("distribution", c);
    check(&e, 4, col(c, 4, "<string"), &["unknown distribution \"phong\"", "beckmann, ggx"]);
}

#[test]
fn parameters_and_document_errors() {
    let c = "<shape type=\"$what\"/>";
    let e = fail("undefined", c);
    check(&e, 4, col(c, 4, "$what"), &["undefined parameter `$what`"]);
    let c = "<shape type=\"cube\">\n</bsdf>";
    let e = fail("xml", c);
    check(&e, 5, col(c, 5, "</bsdf"), &["malformed XML"]);
    let dir = temp_dir("nosensor");
    let path = dir.join("scene.xml");
    std::fs::write(&path, "<scene version=\"3.0.0\"><shape type=\"cube\"/></scene>").unwrap();
    let e = load_scene(&path, &LoadOptions::default()).unwrap_err();
    assert_eq!((e.line, e.column), (None, None));
    assert_eq!(e.to_string(), format!("{}: the scene has no <sensor> (a perspective camera is required)", path.display()));
    std::fs::write(&path, "<scene><shape type=\"cube\"/></scene>").unwrap();
    check(&load_scene(&path, &LoadOptions::default()).unwrap_err(), 1, 1, &["needs a `version` attribute"]);
    std::fs::write(&path, "<scen version=\"3.0.0\"/>").unwrap();
    check(&load_scene(&path, &LoadOptions::default()).unwrap_err(), 1, 1, &["root element is <scen>"]);
    let e = load_scene(Path::new("/nonexistent/scene.xml"), &LoadOptions::default()).unwrap_err();
    assert!(e.to_string().starts_with("/nonexistent/scene.xml: cannot read the scene file"), "{e}");
    // A suite scene with a bad override.
    let options = LoadOptions { defaults: vec![("resx".into(), "wide".into())], ..Default::default() };
    let e = load_scene(&suite_dir().join("ajar/scene.xml"), &options).unwrap_err();
    assert!(e.to_string().contains("malformed integer \"wide\""), "{e}");
}

/// Regression: a truncated file was reported at 1:1 (roxmltree's position for an early
/// end); it is reported where the text ends. Injected bug checked: using `e.pos()` for
/// every XML error again fails here.
#[test]
fn truncated_files_are_reported_where_they_end() {
    let dir = temp_dir("truncated");
    let path = dir.join("scene.xml");
    // Ends inside a tag (end of stream), and after an open element (unclosed root).
    for (text, line, col) in [("<scene version=\"3.0.0\">\n  <shape type=\"cu", 2, 18), ("<scene version=\"3.0.0\">\n<shape type=\"cube\">\n", 3, 1)] {
        std::fs::write(&path, text).unwrap();
        check(&load_scene(&path, &LoadOptions::default()).unwrap_err(), line, col, &["malformed XML", "truncated"]);
    }
}

#[test]
fn garbage_never_panics() {
    // A crude fuzz pass: every prefix of a real scene and byte-flipped variants load or
    // fail cleanly.
    let text = std::fs::read_to_string(suite_dir().join("veach-mis/scene.xml")).unwrap();
    let dir = temp_dir("garbage");
    let path = dir.join("scene.xml");
    let bytes = text.as_bytes();
    let mut state = 0x2545_f491_4f6c_dd1du64;
    for i in 0..400 {
        let mut b = bytes[..(i * 37) % bytes.len()].to_vec();
        if i % 2 == 1 {
            b = bytes.to_vec();
            for _ in 0..4 {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                let at = (state as usize) % b.len();
                b[at] = b"<>\"/=$0.-e ,x"[(state >> 32) as usize % 13];
            }
        }
        std::fs::write(&path, &b).unwrap();
        let _ = load_scene(&path, &LoadOptions::default());
    }
    // Deep nesting is refused, not a stack overflow.
    let deep = format!("<scene version=\"3.0.0\">{}{}</scene>", "<bsdf type=\"twosided\">".repeat(100_000), "</bsdf>".repeat(100_000));
    std::fs::write(&path, deep).unwrap();
    let e = load_scene(&path, &LoadOptions::default()).unwrap_err();
    assert!(e.to_string().contains("nested more than"), "{e}");
    for junk in [&b"ply\nformat ascii 1.0\nelement vertex 18446744073709551615\nproperty float x\nend_header\n"[..], b"ply\n", b"", b"f 1 2 3\nv 1 2"] {
        let _ = super::ply::parse(junk);
        std::fs::write(dir.join("j.obj"), junk).unwrap();
        let _ = super::mesh::load_obj(&dir.join("j.obj"));
    }
}

/// Environment maps: a missing, corrupt or unsupported file and a `to_world` that is not a
/// rotation each name the file (or the transform) and the problem; the scene's other
/// content is never reached.
#[test]
fn envmap_files_fail_with_their_name() {
    let c = "<emitter type=\"envmap\"><string name=\"filename\" value=\"missing.exr\"/></emitter>";
    let e = fail("envmap_missing", c);
    check(&e, 4, col(c, 4, "<string"), &["envmap", "missing.exr"]);
    let c = "<emitter type=\"envmap\"><string name=\"filename\" value=\"sky.exr\"/></emitter>";
    let e = fail_with("envmap_corrupt", c, &[("sky.exr", b"v/1\x01 not an exr at all")], &LoadOptions::default());
    check(&e, 4, col(c, 4, "<string"), &["envmap", "sky.exr"]);
    let c = "<emitter type=\"envmap\"><string name=\"filename\" value=\"sky.png\"/></emitter>";
    let e = fail_with("envmap_png", c, &[("sky.png", b"\x89PNG")], &LoadOptions::default());
    check(&e, 4, col(c, 4, "<string"), &["sky.png", "not a readable PNG"]);
    let c = "<emitter type=\"envmap\"><string name=\"filename\" value=\"sky.tga\"/></emitter>";
    let e = fail_with("envmap_tga", c, &[("sky.tga", b"\0\0\x02")], &LoadOptions::default());
    check(&e, 4, col(c, 4, "<string"), &["sky.tga", "unsupported image format", ".hdr"]);
    let c = "<emitter type=\"envmap\"/>";
    let e = fail("envmap_no_file", c);
    check(&e, 4, col(c, 4, "<emitter"), &["needs a `filename`"]);
    // A valid map, scaled by its transform: refused, at the transform.
    let dir = temp_dir("envmap_scaled");
    crate::image_io::write_exr(&dir.join("sky.exr"), 4, 2, &[[1.0, 1.0, 1.0]; 8]).unwrap();
    let path = dir.join("scene.xml");
    let c = "<emitter type=\"envmap\"><string name=\"filename\" value=\"sky.exr\"/>\n<transform name=\"to_world\"><scale value=\"2\"/></transform></emitter>";
    std::fs::write(&path, format!("<scene version=\"3.0.0\">\n{SENSOR}\n{c}\n</scene>\n")).unwrap();
    let Err(e) = load_scene(&path, &LoadOptions::default()) else { panic!("a scaled envmap loaded") };
    assert!(e.to_string().contains("must be a rotation") && e.to_string().contains(":5:"), "{e}");
}

/// Issue 51: `/dev/zero`, a FIFO or a directory given as the scene, a mesh, a texture or
/// an environment map was read until memory ran out (`std::fs::read`, tobj's reader) or
/// blocked forever (opening a FIFO waits for a writer). Each is refused, naming the file
/// and what it is, before it is opened. Injected bugs checked, under `ulimit -v 4000000`:
/// `std::fs::read` for the scene file again reads `/dev/zero` until it fails with "out of
/// memory"; `File::open` without a bound in `mesh::load_obj` aborts the test process
/// ("memory allocation of 4294967296 bytes failed"); `std::fs::read` in
/// `images::read_exr` blocks on the FIFO until `timeout` kills the test.
#[test]
fn inputs_that_are_not_regular_files_are_refused_by_name() {
    let dir = temp_dir("not_regular");
    let fifo = dir.join("pipe.exr");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs");
    assert!(made.success());
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.png")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.ply")).unwrap();
    std::fs::create_dir(dir.join("folder.exr")).unwrap();
    // The scene file itself.
    for (path, what) in [(Path::new("/dev/zero"), "not a regular file"), (dir.as_path(), "is a directory"), (fifo.as_path(), "not a regular file")] {
        let e = load_scene(path, &LoadOptions::default()).unwrap_err();
        assert!(e.to_string().starts_with(&format!("{}: cannot read the scene file: ", path.display())), "{e}");
        assert!(e.message.contains(what), "{e}");
    }
    // Files the scene names: each error is at the `filename` property and names the file.
    let tex = |file: &str| {
        format!(
            r#"<shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="{file}"/></texture></bsdf></shape>"#
        )
    };
    let cases = [
        (r#"<shape type="obj"><string name="filename" value="/dev/zero"/></shape>"#.to_string(), "/dev/zero", "not a regular file"),
        (r#"<shape type="ply"><string name="filename" value="zero.ply"/></shape>"#.to_string(), "zero.ply", "not a regular file"),
        (tex("zero.png"), "zero.png", "not a regular file"),
        (tex("pipe.exr"), "pipe.exr", "not a regular file"),
        (tex("folder.exr"), "folder.exr", "is a directory"),
        (r#"<emitter type="envmap"><string name="filename" value="pipe.exr"/></emitter>"#.to_string(), "pipe.exr", "not a regular file"),
        (r#"<emitter type="envmap"><string name="filename" value="folder.exr"/></emitter>"#.to_string(), "folder.exr", "is a directory"),
    ];
    for (content, file, what) in cases {
        let path = dir.join("scene.xml");
        std::fs::write(&path, format!("<scene version=\"3.0.0\">\n{SENSOR}\n{content}\n</scene>\n")).unwrap();
        let e = load_scene(&path, &LoadOptions::default()).unwrap_err();
        check(&e, 4, col(&content, 4, "<string"), &[file, what, "only regular files are read"]);
    }
}

/// Issue 51: a `-D` value that does not fit where the scene uses it was reported at the
/// file's line, which shows `$spp`, not the `abc` at fault. The error now names the
/// `-D` that supplied the value, for parse errors (at the attribute) and for range errors
/// found later (at the property). Injected bug checked: without `note_override` in
/// `Parser::attr` the `-D spp=abc` needle is missing.
#[test]
fn a_bad_dash_d_value_names_the_override() {
    let dir = temp_dir("dash_d");
    let path = dir.join("scene.xml");
    let text = "<scene version=\"3.0.0\">\n<default name=\"spp\" value=\"4\"/>\n<default name=\"r\" value=\"1\"/>\n\
        <sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/>\n  <sampler type=\"independent\"><integer name=\"sample_count\" value=\"$spp\"/></sampler></sensor>\n\
        <shape type=\"sphere\"><float name=\"radius\" value=\"${r}\"/></shape></scene>\n";
    std::fs::write(&path, text).unwrap();
    let with = |k: &str, v: &str| LoadOptions { defaults: vec![(k.into(), v.into())], ..Default::default() };
    let e = load_scene(&path, &with("spp", "abc")).unwrap_err();
    check(&e, 5, 67, &["malformed integer \"abc\"", "`-D spp=abc`"]);
    let e = load_scene(&path, &with("spp", "0")).unwrap_err();
    check(&e, 5, 31, &["`sample_count` must be in 1..=", "got 0", "`-D spp=0`"]);
    let e = load_scene(&path, &with("r", "-2")).unwrap_err();
    check(&e, 6, 22, &["sphere `radius` must be positive", "`-D r=-2`"]);
    // The file's own bad value names no override.
    let e = load_scene(&path, &with("r", "1")).map(|_| ()).err();
    assert!(e.is_none(), "{e:?}");
    std::fs::write(&path, text.replace("value=\"4\"", "value=\"four\"")).unwrap();
    let e = load_scene(&path, &LoadOptions::default()).unwrap_err();
    check(&e, 5, 67, &["malformed integer \"four\""]);
    assert!(!e.message.contains("-D"), "{e}");
}

/// Issue 51: `near_clip` and `far_clip`, in nearly every exported scene, were
/// "unreferenced property" errors. They are checked as Mitsuba checks them, accepted
/// with a warning (ember's camera does not clip), and `far_clip` is `thinlens`'s default
/// focus distance. Injected bug checked: with `clip_planes` not called from `sensor`,
/// the first load fails with "unreferenced property `near_clip`" (as before the fix).
#[test]
fn near_and_far_clip_are_accepted_and_checked() {
    let dir = temp_dir("clip");
    let path = dir.join("scene.xml");
    let write = |kind: &str, props: &str| {
        std::fs::write(
            &path,
            format!(
                "<scene version=\"3.0.0\">\n<sensor type=\"{kind}\"><float name=\"fov\" value=\"45\"/>\n  {props}</sensor>\n<shape type=\"cube\"/></scene>\n"
            ),
        )
        .unwrap()
    };
    write("perspective", r#"<float name="near_clip" value="0.1"/><float name="far_clip" value="100"/>"#);
    let loaded = load_scene(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let w = loaded.warnings.join("\n");
    assert!(w.contains("line 2: the sensor's near_clip 0.1 and far_clip 100 are accepted but not modelled"), "{w}");
    write("thinlens", r#"<float name="far_clip" value="7"/><float name="aperture_radius" value="0.1"/>"#);
    let loaded = load_scene(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let (scene, _) = super::tests::build(loaded);
    let lens = format!("{:?}", scene.camera.lens());
    assert!(lens.contains("focus_distance: 7.0"), "{lens}");
    for (props, at, needle) in [
        (r#"<float name="near_clip" value="0"/>"#, "<float", "`near_clip` must be positive, got 0"),
        (
            r#"<float name="near_clip" value="1"/><float name="far_clip" value="1"/>"#,
            "<float name=\"far",
            "`near_clip` (1) must be smaller than `far_clip` (1)",
        ),
        (r#"<float name="near_clip" value="2e4"/>"#, "<float", "`near_clip` (20000) must be smaller than `far_clip` (10000)"),
    ] {
        write("perspective", props);
        let e = load_scene(&path, &LoadOptions::default()).unwrap_err();
        let c = format!("  {props}").find(at).unwrap() as u32 + 1;
        assert_eq!((e.line, e.column), (Some(3), Some(c)), "{e}");
        assert!(e.message.contains(needle), "{e}");
    }
}

/// Issue 51: a triangle with 1e38 coordinates, or a scene 3e7 from its camera, was
/// reported as "zero area" triangles. Each cause is named now: coordinates too large
/// for f32 (the area overflows), precision lost far from the camera (with the distance
/// and the f32 spacing there), or a truly flat triangle. Injected bug checked: with
/// `Dropped::add` counting every drop as degenerate, the first assertion fails on the
/// old messages ("1 of 2 triangles have zero area and were dropped").
#[test]
fn dropped_triangles_say_why() {
    let dir = temp_dir("dropped");
    std::fs::write(dir.join("huge.obj"), "v 0 0 0\nv 1e38 0 0\nv 0 1e38 0\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 4 5 6\n").unwrap();
    let body = r#"<shape type="obj" id="huge"><string name="filename" value="huge.obj"/></shape>
<shape type="rectangle"><transform name="to_world"><scale value="1e38"/></transform></shape><emitter type="constant"/>"#;
    let loaded = super::tests::load_body(&dir, body, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let w = loaded.warnings.join("\n");
    assert!(w.contains("line 4: <shape type=\"obj\" id=\"huge\">: 1 of 2 triangles have coordinates too large for single precision (up to 1.000e38"), "{w}");
    assert!(w.contains("line 5: <shape type=\"rectangle\">: 2 of 2 triangles have coordinates too large"), "{w}");
    assert!(!w.contains("have zero area"), "{w}");
    // The Cornell box seen from 3e7 away: the camera is moved, the scene is not.
    let path = suite_dir().join("cornell-box/scene.xml");
    let text = std::fs::read_to_string(&path).unwrap();
    let far = text.replacen("</transform>", "<translate x=\"3e7\"/></transform>", 1);
    assert!(far.contains("3e7"));
    let loaded = crate::mitsuba::load_scene_from_str(&far, &path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let w = loaded.warnings.join("\n");
    assert!(w.contains("precision is lost far from the camera") && w.contains("from the camera, where coordinates are 2.000e0 apart"), "{w}");
    assert!(!w.contains("have zero area"), "{w}");
    // A flat triangle is still "zero area".
    std::fs::write(dir.join("flat.obj"), "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n").unwrap();
    let body = r#"<shape type="obj"><string name="filename" value="flat.obj"/><transform name="to_world"><rotate x="1" angle="33"/></transform></shape><emitter type="constant"/>"#;
    let loaded = super::tests::load_body(&dir, body, &LoadOptions::default()).unwrap();
    assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
    assert!(loaded.warnings[0].contains("1 of 1 triangles have zero area"), "{:?}", loaded.warnings);
}
