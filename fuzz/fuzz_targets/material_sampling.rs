//! Material sampling invariants for arbitrary finite directions, roughness, indices of
//! refraction and random numbers (issue 8):
//! - `sample` returns `None` or a unit, finite `wi` with finite non-negative `f`, a
//!   finite `pdf > 0` that (for continuous lobes) equals `pdf(wo, wi)` within 1 % (plus
//!   1e-6 absolute: at grazing angles f32 recomputes cos θ only to ~1e-8), a
//!   finite non-negative `pdf_rev` equal to `pdf_rev(wo, wi)`, and a finite η > 0;
//! - `eval`, `pdf` and `pdf_rev` at an arbitrary second direction are finite and ≥ 0;
//! Materials: diffuse, conductor, rough conductor, dielectric, rough dielectric, smooth
//! plastic (any index), rough plastic (over four prebuilt coatings) and principled (any
//! weights in [0, 1], any index), each optionally
//! two-sided, and any of them with a texel value set in one of its texture slots.
//! - a diffuse surface seen from the front always samples, and at least 30 % of all
//!   inputs not grazing within 1e-3 produce a sample (so the target cannot pass by
//!   rejecting everything).
#![no_main]

use std::sync::OnceLock;

use ember_core::bsdf::{Material, MicrofacetKind, PlasticCoating, TextureSlot, TransportMode};
use ember_core::spectrum::Rgb;
use ember_fuzz::{Bytes, ShareFloor, close, finite_nonneg3};
use libfuzzer_sys::fuzz_target;

static SAMPLED: ShareFloor = ShareFloor::new("material_sampling", 0.3, 4096);

fn colour(b: &mut Bytes) -> Rgb {
    Rgb::new(b.unit(), b.unit(), b.unit())
}

/// Any finite index, often a physical one: the constructors must cope with all of them.
fn ior(b: &mut Bytes) -> f32 {
    match b.u8() % 4 {
        0 => b.finite(),
        1 => b.log_uniform(1e-3, 1e3),
        _ => 1.0 + 2.0 * b.unit(),
    }
}

/// Rough plastic coatings, built once: a coating's tables take up to a second (Beckmann),
/// far too long per input. Extreme roughness and indices on both sides of 1.
fn coatings() -> &'static [PlasticCoating] {
    static C: OnceLock<Vec<PlasticCoating>> = OnceLock::new();
    C.get_or_init(|| {
        [
            (MicrofacetKind::Ggx, 1e-4, 1.49, 1.0),
            (MicrofacetKind::Ggx, 0.3, 1.0, 1.33),
            (MicrofacetKind::Beckmann, 1.0, 2.5, 1.0),
            (MicrofacetKind::Ggx, 5.0, 1e3, 1.0),
        ]
        .into_iter()
        .map(|(k, a, i, e)| Material::plastic_coating(k, a, i, e))
        .collect()
    })
}

/// The material and whether it is diffuse.
fn material(b: &mut Bytes) -> (Material, bool) {
    let distr = if b.u8() & 1 == 0 { MicrofacetKind::Beckmann } else { MicrofacetKind::Ggx };
    let alpha = match b.u8() % 4 {
        0 => b.finite().abs(),
        _ => b.log_uniform(1e-5, 1.0),
    };
    let kind = b.u8() % 8;
    let m = match kind {
        0 => Material::diffuse(colour(b)),
        1 => Material::conductor(Rgb::splat(ior(b)), Rgb::splat(b.log_uniform(1e-3, 10.0)), colour(b)),
        2 => Material::rough_conductor(distr, alpha, Rgb::new(ior(b), ior(b), ior(b)), Rgb::splat(b.log_uniform(1e-3, 10.0)), colour(b)),
        3 => Material::dielectric(ior(b), ior(b), colour(b), colour(b)),
        4 => Material::rough_dielectric(distr, alpha, ior(b), ior(b), colour(b), colour(b)),
        5 => Material::plastic(ior(b), ior(b), colour(b), colour(b), b.u8() & 1 == 1),
        7 => Material::principled(ember_core::bsdf::PrincipledParams {
            base_color: colour(b),
            roughness: alpha.min(1e3),
            anisotropic: b.unit(),
            metallic: b.unit(),
            spec_tint: b.unit(),
            sheen: b.unit(),
            sheen_tint: b.unit(),
            flatness: b.unit(),
            clearcoat: b.unit(),
            clearcoat_gloss: b.unit(),
            spec_trans: b.unit(),
            eta: ior(b),
            ..Default::default()
        }),
        _ => {
            let c = &coatings()[b.u8() as usize % coatings().len()];
            Material::rough_plastic_coated(c, colour(b), colour(b), b.u8() & 1 == 1)
        }
    };
    // A texture's value at a hit replaces a parameter (the way `Scene::material` reads it).
    let m = match b.u8() % 5 {
        0 => m.with_texel(TextureSlot::Diffuse, colour(b)),
        1 => m.with_texel(TextureSlot::SpecularReflectance, colour(b)),
        2 => m.with_texel(TextureSlot::SpecularTransmittance, colour(b)),
        3 => m.with_texel(TextureSlot::Roughness, colour(b)),
        _ => m,
    };
    (if b.u8() & 1 == 1 { m.two_sided() } else { m }, kind == 0)
}

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes::new(data);
    let (m, diffuse) = material(&mut b);
    let mode = if b.u8() & 1 == 0 { TransportMode::Radiance } else { TransportMode::Importance };
    let (Some(wo), Some(w2)) = (b.direction(), b.direction()) else { return };
    let (u_lobe, u) = (b.unit(), b.unit2());

    // Arbitrary pairs: finite, non-negative.
    let f = m.eval(wo, w2, mode);
    assert!(finite_nonneg3(f.to_array()), "eval({wo:?}, {w2:?}) = {f:?} for {m:?}");
    for p in [m.pdf(wo, w2, mode).value(), m.pdf_rev(wo, w2, mode).value()] {
        assert!(p.is_finite() && p >= 0.0, "pdf {p} at ({wo:?}, {w2:?}) for {m:?}");
    }

    let s = m.sample(wo, u_lobe, u, mode);
    // u on the unit square's lower edges maps to the disk's rim, i.e. the horizon,
    // where the cosine density is 0: None is right there (found by this target).
    if diffuse && wo.z > 1e-3 && u.x > 0.0 && u.y > 0.0 {
        assert!(s.is_some(), "diffuse seen from the front did not sample: wo {wo:?}, u {u:?}");
    }
    if wo.z.abs() > 1e-3 {
        SAMPLED.record(s.is_some());
    }
    let Some(s) = s else { return };
    let ctx = || format!("{m:?}, {mode:?}, wo {wo:?}, u_lobe {u_lobe}, u {u:?}, sample {s:?}");
    assert!(s.wi.is_finite() && (s.wi.length() - 1.0).abs() < 1e-4, "wi not unit: {}", ctx());
    assert!(finite_nonneg3(s.f.to_array()), "f: {}", ctx());
    assert!(s.pdf.value().is_finite() && s.pdf.value() > 0.0, "pdf: {}", ctx());
    assert!(s.pdf_rev.value().is_finite() && s.pdf_rev.value() >= 0.0, "pdf_rev: {}", ctx());
    assert!(s.eta.is_finite() && s.eta > 0.0, "eta: {}", ctx());
    if !s.is_delta {
        let pdf = m.pdf(wo, s.wi, mode).value();
        assert!(close(pdf, s.pdf.value(), 1e-2, 1e-6), "pdf(wo, wi) = {pdf}: {}", ctx());
        let pdf_rev = m.pdf_rev(wo, s.wi, mode).value();
        assert!(close(pdf_rev, s.pdf_rev.value(), 1e-2, 1e-6), "pdf_rev(wo, wi) = {pdf_rev}: {}", ctx());
    }
});
