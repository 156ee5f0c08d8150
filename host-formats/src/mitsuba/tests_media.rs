//! Media in the reader (issue 56): a shape's absorbing `interior` becomes σ_t · scale on
//! its own copy of the material; every medium ember does not render is refused by file,
//! line and column, naming what is supported.

use ember_core::spectrum::Rgb;

use super::LoadOptions;
use super::tests::{SENSOR, build, load_body, temp_dir};
use super::tests_errors::{check, col, fail};

const GLASS: &str = r#"<bsdf type="dielectric" id="glass"/>"#;

/// σ_t · scale lands on the shape's material, and only on it: a second shape with the
/// same BSDF and no medium keeps a material without an interior. Seen failing with
/// `scale` not applied (σ_t read (0.5, 1, 2)).
#[test]
fn an_absorbing_interior_is_read_onto_its_shape() {
    let dir = temp_dir("media_read");
    let body = format!(
        r#"{GLASS}
<shape type="cube"><transform name="to_world"><translate z="5"/></transform><ref id="glass"/><medium type="homogeneous" name="interior"><rgb name="albedo" value="0"/><rgb name="sigma_t" value="0.5, 1, 2"/><float name="scale" value="4"/><boolean name="sample_emitters" value="false"/></medium></shape>
<shape type="sphere"><ref id="glass"/></shape>"#
    );
    let (scene, geometry) = build(load_body(&dir, &body, &LoadOptions::default()).unwrap());
    let cube = geometry.triangles[0].material;
    let sphere = geometry.spheres[0].material;
    assert_ne!(cube, sphere);
    assert_eq!(scene.interior(cube), Some(Rgb::new(2.0, 4.0, 8.0)));
    assert_eq!(scene.interior(sphere), None);
}

/// Scattering (an albedo above 0, or none given: Mitsuba's default is 0.75), exterior,
/// unnamed and non-homogeneous media are each refused at their element, naming the
/// problem. Seen failing with the albedo check removed (the scattering medium loaded).
#[test]
fn media_ember_does_not_render_are_refused_by_line() {
    let shape = |medium: &str| format!("<shape type=\"cube\"><bsdf type=\"dielectric\"/>{medium}</shape>");
    let cases = [
        (
            shape(r#"<medium type="homogeneous" name="interior"><rgb name="albedo" value="0.5, 0, 0"/></medium>"#),
            "<rgb",
            "a scattering medium (albedo (0.5, 0, 0))",
        ),
        (shape(r#"<medium type="homogeneous" name="interior"><float name="sigma_t" value="1"/></medium>"#), "<medium", "the default is 0.75"),
        (shape(r#"<medium type="homogeneous" name="exterior"><float name="albedo" value="0"/></medium>"#), "<medium", "`exterior` medium is not supported"),
        (shape(r#"<medium type="homogeneous"><float name="albedo" value="0"/></medium>"#), "<medium", "needs name=\"interior\""),
        (shape(r#"<medium type="heterogeneous" name="interior"/>"#), "<medium", "unsupported medium type \"heterogeneous\""),
        (
            shape(r#"<medium type="homogeneous" name="interior"><float name="albedo" value="0"/><float name="sigma_t" value="-1"/></medium>"#),
            "<float name=\"sigma_t",
            "non-negative",
        ),
        (
            shape(r#"<medium type="homogeneous" name="interior"><float name="albedo" value="0"/><float name="density" value="1"/></medium>"#),
            "<float name=\"density",
            "density",
        ),
    ];
    for (i, (content, at, needle)) in cases.iter().enumerate() {
        let e = fail(&format!("media_refused_{i}"), content);
        check(&e, 4, col(content, 4, at), &[needle]);
    }
}

/// The interior medium of a 2 × 2 × 2 cube at z = 5 (lines as they fall in the file).
const MEDIUM_CUBE: &str = r#"<shape type="cube"><transform name="to_world"><translate z="5"/></transform><bsdf type="roughdielectric"/><medium type="homogeneous" name="interior"><float name="albedo" value="0"/></medium></shape>"#;

/// Whatever sits inside an absorbing medium is refused at its own line, naming the
/// medium's shape: the camera (here the file's sensor, at the origin, inside a cube
/// around it), a point light, a sphere, another cube (nested media), a shape crossing the
/// boundary; a sensor's or an emitter's own `medium` is refused where it is referenced. A shape resting on
/// the medium's face, one beside it and the medium alone load. Seen failing with the
/// edge-crossing test (`Enclosure::crosses`) left out (the rectangle through the cube,
/// whose corners and edges lie outside it, loaded) and with the reader's check removed
/// (every case loaded).
#[test]
fn whatever_sits_inside_an_absorbing_medium_is_refused_by_line() {
    let camera_inside =
        r#"<shape type="cube"><bsdf type="roughdielectric"/><medium type="homogeneous" name="interior"><float name="albedo" value="0"/></medium></shape>"#;
    let e = fail("media_camera_inside", camera_inside);
    check(&e, 2, 1, &["the sensor's position is inside", "of the shape at line 4", "no camera, light or other shape inside"]);
    let cases = [
        (r#"<emitter type="point"><point name="position" x="0.2" y="0" z="5.3"/></emitter>"#, "this light"),
        (r#"<shape type="sphere"><point name="center" x="0" y="0.5" z="5"/><float name="radius" value="0.2"/></shape>"#, "this sphere"),
        (
            r#"<shape type="cube"><transform name="to_world"><scale value="0.3"/><translate z="5"/></transform><bsdf type="dielectric"/><medium type="homogeneous" name="interior"><float name="albedo" value="0"/></medium></shape>"#,
            "this shape",
        ),
        (r#"<shape type="rectangle"><transform name="to_world"><scale value="3"/><translate z="5"/></transform></shape>"#, "this shape"),
    ];
    for (i, (inside, needle)) in cases.iter().enumerate() {
        let e = fail(&format!("media_inside_{i}"), &format!("{MEDIUM_CUBE}\n{inside}"));
        check(&e, 5, 1, &[needle, "inside (or crosses) the absorbing medium of the shape at line 4"]);
    }
    let fog = r#"<medium type="homogeneous" id="fog"><float name="albedo" value="0"/></medium>"#;
    let endpoints = [
        format!("{fog}\n<sensor type=\"perspective\"><ref name=\"medium\" id=\"fog\"/></sensor>"),
        format!("{SENSOR}\n{fog}\n<emitter type=\"point\"><ref name=\"medium\" id=\"fog\"/></emitter>"),
    ];
    for (i, body) in endpoints.iter().enumerate() {
        let text = format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n");
        let Err(e) = super::load_scene_from_str(&text, &temp_dir(&format!("media_endpoint_{i}")).join("scene.xml"), &LoadOptions::default()) else {
            panic!("a medium around an endpoint loaded")
        };
        let line = if i == 0 { 3 } else { 5 };
        assert_eq!(e.line, Some(line), "{e}");
        assert!(e.to_string().contains("cannot sit in a medium: ember's camera and lights are in vacuum"), "{e}");
    }
    let dir = temp_dir("media_allowed");
    for outside in [
        r#"<shape type="rectangle"><transform name="to_world"><scale value="3"/><translate z="4"/></transform></shape>"#,
        r#"<shape type="cube"><transform name="to_world"><translate x="2.5" z="5"/></transform></shape>"#,
        "",
    ] {
        build(load_body(&dir, &format!("{MEDIUM_CUBE}\n{outside}"), &LoadOptions::default()).unwrap_or_else(|e| panic!("{outside}: {e}")));
    }
}
