//! Media in the reader (issue 56): a shape's absorbing `interior` becomes σ_t · scale on
//! its own copy of the material; every medium ember does not render is refused by file,
//! line and column, naming what is supported.

use ember_core::spectrum::Rgb;

use super::LoadOptions;
use super::tests::{build, load_body, temp_dir};
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
<shape type="cube"><ref id="glass"/><medium type="homogeneous" name="interior"><rgb name="albedo" value="0"/><rgb name="sigma_t" value="0.5, 1, 2"/><float name="scale" value="4"/><boolean name="sample_emitters" value="false"/></medium></shape>
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
