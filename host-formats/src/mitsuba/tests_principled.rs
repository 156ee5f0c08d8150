//! The `principled` BSDF in the reader: Mitsuba's defaults, every parameter read, the
//! `eta`/`specular` exclusion, textured `base_color` and `roughness`, and refusals.

use ember_core::bsdf::{Material, PrincipledParams, TransportMode};
use ember_core::math::{Vec2, Vec3};
use ember_core::spectrum::Rgb;

use super::tests::{build, load_body, temp_dir};
use super::{LoadOptions, load_scene};

/// Material 0 of a scene with one rectangle carrying `bsdf`.
fn material(test: &str, bsdf: &str) -> Result<(ember_core::scene::Scene, Material), String> {
    let dir = temp_dir(test);
    let body = format!(r#"<shape type="rectangle">{bsdf}</shape>"#);
    let loaded = load_body(&dir, &body, &LoadOptions::default()).map_err(|e| e.to_string())?;
    let (scene, _) = build(loaded);
    let m = scene.materials[0];
    Ok((scene, m))
}

/// Same values at a few direction pairs (reflection and transmission).
fn same(a: &Material, b: &Material) -> bool {
    let dirs = [Vec3::new(0.3, 0.1, 0.9).normalize(), Vec3::new(-0.5, 0.2, 0.7).normalize(), Vec3::new(0.2, -0.4, -0.8).normalize(), Vec3::Z];
    dirs.iter().all(|&wo| {
        dirs.iter().all(|&wi| {
            a.eval(wo, wi, TransportMode::Radiance) == b.eval(wo, wi, TransportMode::Radiance)
                && a.pdf(wo, wi, TransportMode::Radiance) == b.pdf(wo, wi, TransportMode::Radiance)
        })
    })
}

/// Defaults are Mitsuba's (base 0.5, roughness 0.5, specular 0.5 → η = 1.5); every
/// parameter reaches the model. Seen failing (with `principled_errors`) when `sheen` was
/// read under the name `sheen_tint` (a typo injected in the reader: "unreferenced
/// property `sheen`").
#[test]
fn principled_parameters_and_defaults() {
    let (_, m) = material("principled_defaults", r#"<bsdf type="principled"/>"#).unwrap();
    assert!(same(&m, &Material::principled(PrincipledParams::default())));
    assert!((PrincipledParams::default().eta - 1.5).abs() < 1e-6);
    let xml = r#"<bsdf type="principled"><rgb name="base_color" value="0.8, 0.2, 0.1"/><float name="roughness" value="0.3"/>
        <float name="anisotropic" value="0.4"/><float name="metallic" value="0.2"/><float name="spec_tint" value="0.3"/>
        <float name="sheen" value="0.6"/><float name="sheen_tint" value="0.5"/><float name="flatness" value="0.25"/>
        <float name="clearcoat" value="0.7"/><float name="clearcoat_gloss" value="0.9"/><float name="spec_trans" value="0.35"/>
        <float name="eta" value="1.33"/></bsdf>"#;
    let (_, m) = material("principled_all", xml).unwrap();
    let want = PrincipledParams {
        base_color: Rgb::new(0.8, 0.2, 0.1),
        roughness: 0.3,
        anisotropic: 0.4,
        metallic: 0.2,
        spec_tint: 0.3,
        sheen: 0.6,
        sheen_tint: 0.5,
        flatness: 0.25,
        clearcoat: 0.7,
        clearcoat_gloss: 0.9,
        spec_trans: 0.35,
        eta: 1.33,
        ..PrincipledParams::default()
    };
    assert!(same(&m, &Material::principled(want)));
    assert!(m.has_transmission());
    // `specular` maps to η as Mitsuba: 2/(1 − √(0.08 s)) − 1; 0 with transmission is 10⁻³.
    let (_, m) = material("principled_specular", r#"<bsdf type="principled"><float name="specular" value="0.8"/></bsdf>"#).unwrap();
    assert!(same(&m, &Material::principled(PrincipledParams { eta: PrincipledParams::eta_from_specular(0.8), ..PrincipledParams::default() })));
    let (_, m) =
        material("principled_specular0", r#"<bsdf type="principled"><float name="specular" value="0"/><float name="spec_trans" value="1"/></bsdf>"#).unwrap();
    let p = PrincipledParams { eta: PrincipledParams::eta_from_specular(1e-3), spec_trans: 1.0, ..PrincipledParams::default() };
    assert!(same(&m, &Material::principled(p)));
}

/// `base_color` and `roughness` take textures (roughness reads the texel's luminance);
/// a checkerboard's two squares give the two materials.
#[test]
fn principled_textures() {
    let xml = r#"<bsdf type="principled"><texture type="checkerboard" name="base_color"><rgb name="color0" value="1, 0, 0"/><rgb name="color1" value="0, 0, 1"/></texture>
        <texture type="checkerboard" name="roughness"><float name="color0" value="0.2"/><float name="color1" value="0.9"/></texture></bsdf>"#;
    let (scene, _) = material("principled_textures", xml).unwrap();
    let (a, b) = (scene.material(0, Vec2::new(0.25, 0.25)), scene.material(0, Vec2::new(0.75, 0.25)));
    for (m, base, roughness) in [(&a, Rgb::new(1.0, 0.0, 0.0), 0.2), (&b, Rgb::new(0.0, 0.0, 1.0), 0.9)] {
        let roughness = Rgb::splat(roughness).luminance();
        let want = Material::principled(PrincipledParams { base_color: base, roughness, ..PrincipledParams::default() });
        assert!(same(m, &want), "{base:?} {roughness}");
    }
}

/// Bad input is refused with the parameter named: both `eta` and `specular`, weights
/// outside [0, 1], an unknown parameter, a texture on a float-only parameter.
#[test]
fn principled_errors() {
    let cases = [
        (r#"<float name="eta" value="1.4"/><float name="specular" value="0.5"/>"#, "either `eta` or `specular`"),
        (r#"<float name="metallic" value="1.5"/>"#, "`metallic` must lie in [0, 1]"),
        (r#"<float name="anisotropic" value="-0.1"/>"#, "`anisotropic` must lie in [0, 1]"),
        (r#"<float name="sheen" value="-1"/>"#, "`sheen` must be finite and non-negative"),
        (r#"<float name="eta" value="0"/>"#, "`eta` must be positive"),
        (r#"<float name="alpha" value="0.1"/>"#, "alpha"),
        (r#"<texture type="checkerboard" name="metallic"/>"#, "no textured parameter `metallic`"),
    ];
    for (i, (inner, needle)) in cases.iter().enumerate() {
        let dir = temp_dir(&format!("principled_err{i}"));
        let path = dir.join("scene.xml");
        let xml = format!("<scene version=\"3.0.0\"><shape type=\"rectangle\"><bsdf type=\"principled\">{inner}</bsdf></shape></scene>");
        std::fs::write(&path, xml).unwrap();
        let e = load_scene(&path, &LoadOptions::default()).err().unwrap_or_else(|| panic!("{inner}: loaded"));
        assert!(e.to_string().contains(needle), "{inner}: {e}");
    }
}
