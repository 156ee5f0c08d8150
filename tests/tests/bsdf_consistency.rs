//! Consistency of the materials' `sample`, `eval` and `pdf`, their reciprocity and
//! adjoint relations, normalisation of the densities, and freedom from NaN/∞.
//!
//! Conventions checked (see `ember_core::bsdf`): eval(wo, wi) in Radiance mode is the
//! BSDF for light arriving along wi and leaving along wo, so for transmission it carries
//! η_wo² (the index of wo's medium, squared) and obeys f(wo, wi)/η_wo² = f(wi, wo)/η_wi²
//! (Veach's thesis §5.2); Importance mode is the adjoint, f*(wo, wi) = f(wi, wo).
//!
//! Injected bugs seen to make the statistical test (`pdf_integrates_to_sampled_fraction`)
//! fail, each reverted afterwards:
//! - the transmission Jacobian with 1/η² in place of η² in `RoughDielectric::pdf`
//!   (glass at normal incidence: ∫pdf = 0.23 against a sampled fraction of 1);
//! - `visible_pdf` without the G1(wo, m) factor (Beckmann α = 0.1 at 88°: ∫pdf = 1.38
//!   against 0.983).
//!
//! The deterministic tests were also seen to fail on injected bugs: the Radiance-mode
//! scale η² instead of 1/η² in the rough dielectric (`reciprocity_and_adjoint`), and
//! `pdf_rev` of a sample computed as pdf(wo, wi) (`sample_matches_eval_and_pdf`).

use ember_core::bsdf::{Material, MicrofacetKind, TransportMode, shading_normal_correction};
use ember_core::math::Vec3;
use ember_core::rng::{SampleStream, Stream};
use ember_core::spectrum::Rgb;
use ember_tests::chi2::sidak;
use ember_tests::stats::normal_two_sided_p;
use glam::Vec2;

const KINDS: [MicrofacetKind; 2] = [MicrofacetKind::Beckmann, MicrofacetKind::Ggx];
const ALPHAS: [f32; 4] = [0.01, 0.1, 0.5, 1.0];
const MODES: [TransportMode; 2] = [TransportMode::Radiance, TransportMode::Importance];

/// A named material and, for dielectrics, η_int/η_ext.
#[derive(Clone, Debug)]
struct Named {
    name: String,
    material: Material,
    eta: Option<f32>,
    alpha: f32,
}

fn gold() -> (Rgb, Rgb) {
    (Rgb::new(0.143, 0.375, 1.442), Rgb::new(3.98, 2.39, 1.60))
}

/// Every continuous material under test.
fn materials() -> Vec<Named> {
    let mut v = vec![
        Named { name: "diffuse".into(), material: Material::diffuse(Rgb::new(0.8, 0.5, 0.2)), eta: None, alpha: 1.0 },
        Named { name: "twosided diffuse".into(), material: Material::diffuse(Rgb::splat(0.6)).two_sided(), eta: None, alpha: 1.0 },
    ];
    let (eta, k) = gold();
    for kind in KINDS {
        for alpha in ALPHAS {
            v.push(Named {
                name: format!("rough conductor {kind:?} α={alpha}"),
                material: Material::rough_conductor(kind, alpha, eta, k, Rgb::new(1.0, 0.9, 0.8)),
                eta: None,
                alpha,
            });
            for (int, ext) in [(1.5f32, 1.0f32), (1.0, 1.33)] {
                v.push(Named {
                    name: format!("rough dielectric {kind:?} α={alpha} η={int}/{ext}"),
                    material: Material::rough_dielectric(kind, alpha, int, ext, Rgb::new(1.0, 0.9, 0.8), Rgb::new(0.7, 0.8, 1.0)),
                    eta: Some(int / ext),
                    alpha,
                });
            }
        }
        v.push(Named {
            name: format!("rough plastic {kind:?} α=0.2"),
            material: Material::rough_plastic(kind, 0.2, 1.49, 1.000277, Rgb::new(0.7, 0.15, 0.1), Rgb::ONE, false),
            eta: None,
            alpha: 0.2,
        });
        v.push(Named {
            name: format!("twosided rough conductor {kind:?} α=0.3"),
            material: Material::rough_conductor(kind, 0.3, eta, k, Rgb::ONE).two_sided(),
            eta: None,
            alpha: 0.3,
        });
    }
    v
}

fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn close(a: f32, b: f32, rel: f32, abs: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + abs
}

fn close_rgb(a: Rgb, b: Rgb, rel: f32, abs: f32) -> bool {
    (0..3).all(|i| close(a[i], b[i], rel, abs))
}

/// η of the medium on `w`'s side of a dielectric with η_int/η_ext = `eta` (outside = 1).
fn eta_of_side(w: Vec3, eta: f32) -> f32 {
    if w.z > 0.0 { 1.0 } else { eta }
}

#[test]
fn sample_matches_eval_and_pdf() {
    for m in materials() {
        let mut produced = 0;
        for k in 0..4000u32 {
            let mut rng = SampleStream::for_sample(11, Stream::Aux, k, 0, 0);
            let wo = uniform_sphere(rng.next_2d());
            let mode = MODES[(k % 2) as usize];
            let (u_lobe, u) = (rng.next_f32(), rng.next_2d());
            let Some(s) = m.material.sample(wo, u_lobe, u, mode) else { continue };
            produced += 1;
            let ctx = || format!("{}: wo {wo:?} wi {:?} {mode:?}", m.name, s.wi);
            assert!(!s.is_delta, "{}", ctx());
            assert!((s.wi.length() - 1.0).abs() < 1e-5, "not unit: {}", ctx());
            assert_eq!(s.is_transmission, s.wi.z * wo.z < 0.0, "{}", ctx());
            let pdf = m.material.pdf(wo, s.wi, mode).value();
            assert!(close(s.pdf.value(), pdf, 1e-3, 0.0) && pdf > 0.0, "pdf {} vs {pdf}: {}", s.pdf.value(), ctx());
            let pdf_rev = m.material.pdf(s.wi, wo, mode).value();
            assert!(close(s.pdf_rev.value(), pdf_rev, 1e-3, 0.0), "pdf_rev {} vs {pdf_rev}: {}", s.pdf_rev.value(), ctx());
            assert_eq!(m.material.pdf_rev(wo, s.wi, mode), m.material.pdf(s.wi, wo, mode));
            let f = m.material.eval(wo, s.wi, mode);
            assert!(close_rgb(s.f, f, 1e-3, 0.0), "f {:?} vs {f:?}: {}", s.f, ctx());
            match (s.is_transmission, m.eta) {
                (true, Some(eta)) => {
                    let eta_it = eta_of_side(s.wi, eta) / eta_of_side(wo, eta);
                    assert!(close(s.eta, eta_it, 1e-6, 0.0), "eta {} vs {eta_it}: {}", s.eta, ctx());
                }
                _ => assert_eq!(s.eta, 1.0, "{}", ctx()),
            }
        }
        assert!(produced > 1000, "{}: only {produced} samples", m.name);
    }
}

/// `eval_pdfs` is `eval`, `pdf` and `pdf_rev`, bit for bit, for every material and mode,
/// with directions drawn uniformly (two-sided materials seen from different sides by wo
/// and wi included), sampled (non-zero values at low roughness) and grazing. Seen to fail
/// on injected bugs: the reversed density with G1(wo) in place of G1(wi) (rough
/// conductor), and the reversed density of the other materials taken forward. (Removing
/// the fallback for wo and wi on different sides of a two-sided material did not make it
/// fail: the two-sided materials only reflect, so every value is zero there either way.)
#[test]
fn eval_pdfs_is_the_three_calls() {
    let bits = |c: Rgb| [c.r.to_bits(), c.g.to_bits(), c.b.to_bits()];
    for m in materials() {
        let mut nonzero = 0;
        for k in 0..3000u32 {
            let mut rng = SampleStream::for_sample(31, Stream::Aux, k, 0, 0);
            let wo = uniform_sphere(rng.next_2d());
            let mode = MODES[(k % 2) as usize];
            let (u_lobe, u, u_wi) = (rng.next_f32(), rng.next_2d(), rng.next_2d());
            let wi = match k % 3 {
                0 => uniform_sphere(u_wi),
                1 => match m.material.sample(wo, u_lobe, u, mode) {
                    Some(s) => s.wi,
                    None => continue,
                },
                _ => Vec3::new(u_wi.x - 0.5, u_wi.y - 0.5, if k % 2 == 0 { 0.0 } else { -1e-6 }).normalize(),
            };
            let (f, pdf, pdf_rev) = m.material.eval_pdfs(wo, wi, mode);
            let ctx = || format!("{}: wo {wo:?} wi {wi:?} {mode:?}", m.name);
            assert_eq!(bits(f), bits(m.material.eval(wo, wi, mode)), "f: {}", ctx());
            assert_eq!(pdf.value().to_bits(), m.material.pdf(wo, wi, mode).value().to_bits(), "pdf: {}", ctx());
            assert_eq!(pdf_rev.value().to_bits(), m.material.pdf_rev(wo, wi, mode).value().to_bits(), "pdf_rev: {}", ctx());
            nonzero += (pdf.value() > 0.0 && pdf_rev.value() > 0.0 && !f.is_black()) as u32;
        }
        assert!(nonzero > 300, "{}: only {nonzero} non-zero triples", m.name);
    }
}

/// Midpoint quadrature of the pdf over the part of the sphere on `side` (+1: wo's side,
/// −1: the other), in coordinates concentrated around `axis`: θ' = π s^c.
fn integrate_pdf(material: &Material, wo: Vec3, side: f32, axis: Vec3, c: f64) -> f64 {
    // The narrowest lobes (c = 3), cut by the horizon at grazing incidence, need the most points.
    let (ns, np) = if c >= 3.0 { (1500usize, 360usize) } else { (800, 200) };
    let frame = ember_core::math::Frame::from_normal(axis);
    let mut total = 0.0;
    for i in 0..ns {
        let s = (i as f64 + 0.5) / ns as f64;
        let theta = std::f64::consts::PI * s.powf(c);
        let dtheta = std::f64::consts::PI * c * s.powf(c - 1.0) / ns as f64;
        let (st, ct) = theta.sin_cos();
        let mut row = 0.0;
        for j in 0..np {
            let phi = (j as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
            let w = frame.to_world(Vec3::new((st * phi.cos()) as f32, (st * phi.sin()) as f32, ct as f32));
            if w.z * wo.z * side > 0.0 {
                row += material.pdf(wo, w, TransportMode::Radiance).value() as f64;
            }
        }
        total += row * st * dtheta * std::f64::consts::TAU / np as f64;
    }
    total
}

fn concentration(alpha: f32) -> f64 {
    if alpha <= 0.01 {
        3.0
    } else if alpha <= 0.1 {
        2.0
    } else {
        1.0
    }
}

#[test]
fn pdf_integrates_to_sampled_fraction() {
    let cases: Vec<(Named, Vec3)> = materials()
        .into_iter()
        .flat_map(|m| {
            let t = |deg: f32, inside: bool| {
                let r = deg.to_radians();
                Vec3::new(r.sin() * 0.8, r.sin() * 0.6, if inside { -r.cos() } else { r.cos() })
            };
            let mut wos = vec![t(0.0, false), t(60.0, false), t(88.0, false)];
            if m.eta.is_some() || m.name.starts_with("twosided") {
                wos.extend([t(30.0, true), t(75.0, true)]);
            }
            wos.into_iter().map(move |wo| (m.clone(), wo))
        })
        .collect();
    let significance = sidak(0.01, cases.len());
    const N: u32 = 100_000;
    for (i, (m, wo)) in cases.iter().enumerate() {
        let wo = *wo;
        // Fraction of calls that produce a sample.
        let mut some = 0u32;
        for k in 0..N {
            let mut rng = SampleStream::for_sample(0x1a7e + i as u64, Stream::Aux, k, 0, 0);
            some += m.material.sample(wo, rng.next_f32(), rng.next_2d(), TransportMode::Radiance).is_some() as u32;
        }
        let fraction = some as f64 / N as f64;
        // ∫pdf: reflection part around the mirror direction, transmission part around the
        // refracted one (or the far pole under total internal reflection).
        let c = concentration(m.alpha);
        let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
        let mut integral = integrate_pdf(&m.material, wo, 1.0, mirror, c);
        if let Some(eta) = m.eta {
            let eta_it = if wo.z > 0.0 { eta } else { 1.0 / eta };
            let sin2_t = (1.0 - wo.z * wo.z) / (eta_it * eta_it);
            let axis = if sin2_t < 1.0 {
                Vec3::new(-wo.x / eta_it, -wo.y / eta_it, -wo.z.signum() * (1.0 - sin2_t).sqrt()).normalize()
            } else {
                Vec3::new(0.0, 0.0, -wo.z.signum())
            };
            integral += integrate_pdf(&m.material, wo, -1.0, axis, if sin2_t < 1.0 { c } else { 1.0 });
        }
        // Binomial error of the fraction plus an allowance for the quadrature.
        let sd = (fraction * (1.0 - fraction) / N as f64).max(1e-12).sqrt();
        let quad = 1.5e-3;
        let excess = ((integral - fraction).abs() - quad).max(0.0);
        let p = normal_two_sided_p(excess / sd);
        println!("{} θo={:.0}°: sampled {fraction:.5}, ∫pdf {integral:.5}, p = {p:.3}", m.name, wo.z.acos().to_degrees());
        assert!(p >= significance, "{} wo {wo:?}: ∫pdf = {integral} but sampled fraction {fraction} (p = {p:e})", m.name);
    }
}

#[test]
fn reciprocity_and_adjoint() {
    for m in materials() {
        let mut checked = 0;
        for k in 0..3000u32 {
            let mut rng = SampleStream::for_sample(23, Stream::Aux, k, 0, 0);
            let wo = uniform_sphere(rng.next_2d());
            // Half the pairs from the material's own sampler (where values are large),
            // half uniform.
            let wi = if k % 2 == 0 {
                match m.material.sample(wo, rng.next_f32(), rng.next_2d(), TransportMode::Radiance) {
                    Some(s) => s.wi,
                    None => continue,
                }
            } else {
                uniform_sphere(rng.next_2d())
            };
            let fr = m.material.eval(wo, wi, TransportMode::Radiance);
            let fr_swap = m.material.eval(wi, wo, TransportMode::Radiance);
            let fi = m.material.eval(wo, wi, TransportMode::Importance);
            let ctx = format!("{}: wo {wo:?} wi {wi:?}", m.name);
            // Adjoint: f*(wo, wi) = f(wi, wo).
            assert!(close_rgb(fi, fr_swap, 2e-3, 1e-6), "adjoint {fi:?} vs {fr_swap:?}: {ctx}");
            if wo.z * wi.z > 0.0 {
                assert!(close_rgb(fr, fr_swap, 2e-3, 1e-6), "reflection reciprocity {fr:?} vs {fr_swap:?}: {ctx}");
            } else if let Some(eta) = m.eta {
                // f(wo, wi)/η_wo² = f(wi, wo)/η_wi².
                let (eo, ei) = (eta_of_side(wo, eta), eta_of_side(wi, eta));
                assert!(close_rgb(fr * (1.0 / (eo * eo)), fr_swap * (1.0 / (ei * ei)), 2e-3, 1e-6), "generalised reciprocity {fr:?} vs {fr_swap:?}: {ctx}");
            } else {
                assert!(fr.is_black() && fr_swap.is_black(), "{ctx}");
            }
            if !fr.is_black() {
                checked += 1;
            }
        }
        assert!(checked > 300, "{}: only {checked} non-zero pairs", m.name);
    }
}

#[test]
fn one_sided_materials_are_black_from_behind() {
    let (eta, k) = gold();
    for material in [Material::diffuse(Rgb::ONE), Material::rough_conductor(MicrofacetKind::Ggx, 0.3, eta, k, Rgb::ONE), Material::conductor(eta, k, Rgb::ONE)]
    {
        for k in 0..500u32 {
            let mut rng = SampleStream::for_sample(5, Stream::Aux, k, 0, 0);
            let (wo, wi) = (uniform_sphere(rng.next_2d()), uniform_sphere(rng.next_2d()));
            if wo.z > 0.0 && wi.z > 0.0 {
                continue;
            }
            for mode in MODES {
                assert!(material.eval(wo, wi, mode).is_black());
                assert_eq!(material.pdf(wo, wi, mode).value(), 0.0);
            }
            if wo.z <= 0.0 {
                assert!(material.sample(wo, 0.5, rng.next_2d(), TransportMode::Radiance).is_none());
            }
        }
        // Two-sided: the back mirrors the front.
        let two = material.two_sided();
        let (wo, wi) = (Vec3::new(0.3, 0.1, 0.9).normalize(), Vec3::new(-0.5, 0.2, 0.6).normalize());
        let flip = |w: Vec3| Vec3::new(w.x, w.y, -w.z);
        let mode = TransportMode::Radiance;
        assert_eq!(two.eval(flip(wo), flip(wi), mode), material.eval(wo, wi, mode));
        assert_eq!(two.pdf(flip(wo), flip(wi), mode), material.pdf(wo, wi, mode));
        assert!(two.eval(flip(wo), wi, mode).is_black());
        if let Some(s) = two.sample(flip(wo), 0.5, Vec2::new(0.3, 0.6), mode) {
            assert!(s.wi.z < 0.0);
        }
    }
    assert!(Material::dielectric(1.5, 1.0, Rgb::ONE, Rgb::ONE).two_sided().has_transmission());
}

#[test]
fn flags() {
    let (eta, k) = gold();
    let g = MicrofacetKind::Ggx;
    assert!(Material::conductor(eta, k, Rgb::ONE).is_delta());
    assert!(Material::dielectric(1.5, 1.0, Rgb::ONE, Rgb::ONE).is_delta());
    assert!(!Material::rough_conductor(g, 1e-4, eta, k, Rgb::ONE).is_delta());
    assert!(!Material::diffuse(Rgb::ONE).is_delta());
    assert!(Material::rough_dielectric(g, 0.1, 1.5, 1.0, Rgb::ONE, Rgb::ONE).has_transmission());
    assert!(!Material::rough_conductor(g, 0.1, eta, k, Rgb::ONE).has_transmission());
    // Dirac materials have no density and no value.
    let (wo, wi) = (Vec3::new(0.3, 0.0, 0.954).normalize(), Vec3::new(-0.3, 0.0, 0.954).normalize());
    for m in [Material::conductor(eta, k, Rgb::ONE), Material::dielectric(1.5, 1.0, Rgb::ONE, Rgb::ONE)] {
        assert!(m.eval(wo, wi, TransportMode::Radiance).is_black());
        assert_eq!(m.pdf(wo, wi, TransportMode::Radiance).value(), 0.0);
    }
    // Albedo hints: plausible reflectance-like colours.
    let hint = Material::rough_conductor(g, 0.2, eta, k, Rgb::ONE).albedo_hint();
    assert!(hint.r > 0.9 && hint.b < 0.5, "gold {hint:?}");
    let glass = Material::dielectric(1.5, 1.0, Rgb::ONE, Rgb::ONE).albedo_hint();
    assert!((glass.r - 1.0).abs() < 1e-6);
    assert_eq!(Material::diffuse(Rgb::new(0.1, 0.2, 0.3)).albedo_hint(), Rgb::new(0.1, 0.2, 0.3));
}

#[test]
fn shading_normal_correction_values() {
    let ng = Vec3::Z;
    let ns = Vec3::new(0.2, 0.0, 1.0).normalize();
    let (wo, wi) = (Vec3::new(0.5, 0.1, 0.8).normalize(), Vec3::new(-0.4, 0.3, 0.7).normalize());
    assert_eq!(shading_normal_correction(TransportMode::Radiance, wo, wi, ng, ns), 1.0);
    assert!((shading_normal_correction(TransportMode::Importance, wo, wi, ng, ng) - 1.0).abs() < 1e-6);
    let c = shading_normal_correction(TransportMode::Importance, wo, wi, ng, ns);
    let expected = wo.dot(ns).abs() * wi.dot(ng).abs() / (wo.dot(ng).abs() * wi.dot(ns).abs());
    assert!((c - expected).abs() < 1e-6);
    // wi perpendicular to ns, or wo grazing the geometric surface: 0, not ∞/NaN.
    let wi_perp = Vec3::new(-ns.z, 0.0, ns.x);
    assert_eq!(shading_normal_correction(TransportMode::Importance, wo, wi_perp, ng, ns), 0.0);
    assert_eq!(shading_normal_correction(TransportMode::Importance, Vec3::X, wi, ng, ns), 0.0);
}

/// Non-finiteness sweep: roughness down to 10⁻⁵, incidence up to 89.999°, relative
/// indices near 1 and large, both sides, both modes, extreme random numbers.
#[test]
fn no_nan_or_inf_anywhere() {
    let alphas = [1e-5f32, 1e-4, 1e-3, 0.01, 0.1, 0.5, 1.0];
    let angles = [0.0f32, 10.0, 45.0, 80.0, 89.0, 89.9, 89.99, 89.999];
    let etas = [1.0001f32, 1.5, 4.0];
    let edge = [0.0f32, 1e-7, 0.25, 0.5, 0.999, 1.0 - f32::EPSILON / 2.0];
    let (geta, gk) = gold();
    let mut materials = vec![
        Material::diffuse(Rgb::ONE),
        Material::diffuse(Rgb::ONE).two_sided(),
        Material::conductor(geta, gk, Rgb::ONE),
        Material::conductor(Rgb::splat(0.0), Rgb::splat(0.0), Rgb::ONE),
    ];
    for kind in KINDS {
        for alpha in alphas {
            materials.push(Material::rough_conductor(kind, alpha, geta, gk, Rgb::ONE).two_sided());
            materials.push(Material::rough_conductor(kind, alpha, Rgb::splat(0.0), Rgb::splat(1.0), Rgb::ONE));
            for eta in etas {
                materials.push(Material::rough_dielectric(kind, alpha, eta, 1.0, Rgb::ONE, Rgb::ONE));
                materials.push(Material::rough_dielectric(kind, alpha, 1.0, eta, Rgb::ONE, Rgb::ONE));
            }
        }
    }
    for eta in etas {
        materials.push(Material::dielectric(eta, 1.0, Rgb::ONE, Rgb::ONE));
        materials.push(Material::dielectric(1.0, eta, Rgb::ONE, Rgb::ONE));
    }
    let mut samples = 0usize;
    for (mi, material) in materials.iter().enumerate() {
        for &deg in &angles {
            for inside in [false, true] {
                let t = (deg as f64).to_radians();
                let z = if inside { -t.cos() } else { t.cos() };
                let wo = Vec3::new((t.sin() * 0.6) as f32, (t.sin() * 0.8) as f32, z as f32);
                let mut rng = SampleStream::for_sample(99, Stream::Aux, mi as u32, deg.to_bits(), inside as u32);
                let mut us: Vec<Vec2> = edge.iter().flat_map(|&a| edge.iter().map(move |&b| Vec2::new(a, b))).collect();
                us.extend((0..64).map(|_| rng.next_2d()));
                for (j, &u) in us.iter().enumerate() {
                    for mode in MODES {
                        let u_lobe = edge[j % edge.len()];
                        let ctx = || format!("{material:?} wo {wo:?} u {u:?} u_lobe {u_lobe} {mode:?}");
                        if let Some(s) = material.sample(wo, u_lobe, u, mode) {
                            samples += 1;
                            assert!(s.wi.is_finite() && (s.wi.length() - 1.0).abs() < 1e-4, "wi {:?}: {}", s.wi, ctx());
                            assert!(s.f.is_valid_radiance(), "f {:?}: {}", s.f, ctx());
                            assert!(s.pdf.value() > 0.0 && s.pdf.value().is_finite(), "pdf {:?}: {}", s.pdf, ctx());
                            assert!(s.pdf_rev.value() >= 0.0 && s.pdf_rev.value().is_finite(), "pdf_rev {:?}: {}", s.pdf_rev, ctx());
                            assert!(s.eta > 0.0 && s.eta.is_finite(), "{}", ctx());
                            let f = material.eval(wo, s.wi, mode);
                            assert!(f.is_valid_radiance(), "{}", ctx());
                        }
                        // Arbitrary and special directions through eval and pdf.
                        let wi_rand = uniform_sphere(u);
                        for wi in [wi_rand, Vec3::new(-wo.x, -wo.y, wo.z), -wo, wo, Vec3::Z, -Vec3::Z, Vec3::X] {
                            let f = material.eval(wo, wi, mode);
                            let p = material.pdf(wo, wi, mode).value();
                            let pr = material.pdf_rev(wo, wi, mode).value();
                            assert!(f.is_valid_radiance(), "eval {f:?} at wi {wi:?}: {}", ctx());
                            assert!(p >= 0.0 && p.is_finite() && pr >= 0.0 && pr.is_finite(), "pdf {p} {pr} at wi {wi:?}: {}", ctx());
                        }
                    }
                }
            }
        }
    }
    assert!(samples > 100_000, "{samples}");
    // Exactly grazing wo: no sample.
    for material in &materials {
        assert!(material.sample(Vec3::X, 0.5, Vec2::splat(0.5), TransportMode::Radiance).is_none());
    }
}
