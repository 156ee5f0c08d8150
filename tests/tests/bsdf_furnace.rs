//! White furnace: the directional albedo ρ(wo) = ∫ f(wo, wi) |cos θi| dwi of white
//! materials, estimated by sampling.
//!
//! Energy conservation is a statement about the physical BSDF with light arriving along
//! wo, i.e. about the adjoint, so ρ is estimated in [`TransportMode::Importance`]
//! (for reflection the modes agree). Checks:
//! - ρ ≤ 1 everywhere (up to statistical error) for every white material;
//! - the BSDF-sampling estimate agrees with an independent uniform-sphere estimate of the
//!   same integral (for α ≥ 0.3, where the latter has manageable variance);
//! - ρ = 1 for white diffuse, the F = 1 smooth mirror and the smooth dielectric (R + T);
//!   in Radiance mode the smooth dielectric gives F + (1 − F)/η² instead.
//!
//! Single-scattering energy loss 1 − ρ of the microfacet models (Smith's uncorrelated
//! masking removes the light that would scatter again between facets, and visible normals
//! whose reflection points below the horizon are lost). Measured by this test with
//! 200 000 samples per entry (it now runs 100 000; standard error ≤ 0.15 %), for a rough
//! conductor with F = 1 (η = 0, k = 1) at incidence 0° / 45° / 75° / 89°:
//!
//! | α    | GGX                         | Beckmann                   |
//! |------|-----------------------------|----------------------------|
//! | 0.01 | 0.01 / 0.01 / 0.09 / 9.9 %  | 0 / 0 / 0 / 6.1 %          |
//! | 0.1  | 1.2 / 1.8 / 7.6 / 8.7 %     | 0 / 0 / 2.5 / 5.0 %        |
//! | 0.3  | 12 / 16 / 19 / 12 %         | 0.03 / 3.3 / 9.8 / 4.1 %   |
//! | 0.5  | 31 / 32 / 28 / 19 %         | 5.7 / 13 / 9.9 / 4.4 %     |
//! | 0.75 | 53 / 50 / 40 / 29 %         | 31 / 23 / 11 / 5.5 %       |
//! | 1.0  | 69 / 64 / 51 / 40 %         | 54 / 35 / 15 / 7.7 %       |
//!
//! So a GGX conductor with F = 1 at α = 1 loses ln 2 ≈ 69 % at normal incidence: there
//! D = 1/π, the reflection makes twice the facet angle, and ρ = 1 − ln 2 exactly (checked
//! below). The white rough dielectric (η = 1.5, GGX α = 1) loses 11 % at 0° and 67 % at
//! 89° from outside, 58 % and 64 % from inside; the test prints every entry.
//!
//! Rough plastic with a white base (ρ = 1, polypropylene coating) keeps 0.91 / 0.91 / 0.87
//! at 0° / 45° / 89° for GGX α = 0.1, 0.54 / 0.53 / 0.39 for GGX α = 0.5, 0.97 / 0.97 /
//! 0.94 and 0.74 / 0.73 / 0.75 for Beckmann: Mitsuba's model (its renders are matched in
//! `host-cli/tests/envmap_reference.rs`) loses what the coating's masking removes, on the
//! way in, inside and on the way out.
//!
//! Injected bugs seen to make these tests fail, each reverted afterwards:
//! - rough plastic's base without the 1/η² of leaving the coating: `furnace_rough_plastic`
//!   rejects ρ = 1.97;
//! - smooth plastic's mirror weight without its 1/P(Dirac) (f = R_s F / cos θi):
//!   `furnace_rough_plastic` rejects ρ = 0.964 ± 0.0007 against 1.0011 at 0°
//!   (`bsdf_chi2::plastic_mirror_lobe` rejects its weight too);
//! - the factor 1/4 dropped from the rough conductor's value: `furnace_rough_conductors`
//!   rejects ρ = 4.0;
//! - the factor 1/4 dropped from the rough dielectric's reflection:
//!   `furnace_rough_dielectrics_outside` rejects ρ = 1.12;
//! - the rough dielectric's transmission scale applied in Importance instead of Radiance
//!   mode: `furnace_rough_dielectrics_inside` rejects ρ = 2.2;
//! - the smooth dielectric's Radiance-mode scale (η_t/η_i)² instead of (η_i/η_t)²:
//!   `furnace_smooth_and_diffuse` rejects the Radiance-mode albedo.

use ember_core::bsdf::{Material, MicrofacetKind, TransportMode};
use ember_core::math::Vec3;
use ember_core::rng::{SampleStream, Stream};
use ember_core::spectrum::Rgb;
use ember_tests::chi2::sidak;
use ember_tests::stats::fresnel_f64;
use ember_tests::stats::{MeanVar, normal_two_sided_p};
use glam::Vec2;

const N: u32 = 100_000;
const KINDS: [MicrofacetKind; 2] = [MicrofacetKind::Ggx, MicrofacetKind::Beckmann];
const ALPHAS: [f32; 6] = [0.01, 0.1, 0.3, 0.5, 0.75, 1.0];
const ANGLES: [f32; 4] = [0.0, 45.0, 75.0, 89.0];

fn incident(deg: f32, inside: bool) -> Vec3 {
    let t = deg.to_radians();
    Vec3::new(t.sin() * 0.6, t.sin() * 0.8, if inside { -t.cos() } else { t.cos() })
}

/// ρ(wo) by sampling the material (a `None` sample contributes 0); the channel average.
fn albedo_by_bsdf_sampling(material: &Material, wo: Vec3, mode: TransportMode, seed: u64) -> MeanVar {
    let mut acc = MeanVar::default();
    for k in 0..N {
        let mut rng = SampleStream::for_sample(seed, Stream::Aux, k, 0, 0);
        let w = match material.sample(wo, rng.next_f32(), rng.next_2d(), mode) {
            Some(s) => (s.f * s.wi.z.abs() / s.pdf.value()).average() as f64,
            None => 0.0,
        };
        acc.push(w);
    }
    acc
}

/// ρ(wo) by uniform sampling of the sphere: 4π f |cos θi|.
fn albedo_by_uniform_sampling(material: &Material, wo: Vec3, mode: TransportMode, seed: u64) -> MeanVar {
    let mut acc = MeanVar::default();
    for k in 0..N {
        let mut rng = SampleStream::for_sample(seed ^ 0xffff, Stream::Aux, k, 0, 0);
        let u: Vec2 = rng.next_2d();
        let z = 1.0 - 2.0 * u.x;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * u.y;
        let wi = Vec3::new(r * phi.cos(), r * phi.sin(), z);
        acc.push((material.eval(wo, wi, mode) * (wi.z.abs() * 4.0 * std::f32::consts::PI)).average() as f64);
    }
    acc
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Group {
    Smooth,
    Conductor,
    DielectricOutside,
    DielectricInside,
    Plastic,
}

struct Case {
    group: Group,
    name: String,
    material: Material,
    wo: Vec3,
    alpha: f32,
    /// Exact albedo when known.
    exact: Option<f64>,
}

fn mirror() -> (Rgb, Rgb) {
    (Rgb::splat(0.0), Rgb::splat(1.0))
}

fn cases() -> Vec<Case> {
    let mut v = Vec::new();
    let (eta, k) = mirror();
    for deg in ANGLES {
        let wo = incident(deg, false);
        v.push(Case { group: Group::Smooth, name: format!("diffuse θ={deg}°"), material: Material::diffuse(Rgb::ONE), wo, alpha: 1.0, exact: Some(1.0) });
        v.push(Case {
            group: Group::Smooth,
            name: format!("mirror θ={deg}°"),
            material: Material::conductor(eta, k, Rgb::ONE),
            wo,
            alpha: 0.0,
            exact: Some(1.0),
        });
        for inside in [false, true] {
            v.push(Case {
                group: Group::Smooth,
                name: format!("smooth dielectric θ={deg}° inside={inside}"),
                material: Material::dielectric(1.5, 1.0, Rgb::ONE, Rgb::ONE),
                wo: incident(deg, inside),
                alpha: 0.0,
                exact: Some(1.0),
            });
        }
        v.push(Case {
            group: Group::Smooth,
            name: format!("twosided diffuse back θ={deg}°"),
            material: Material::diffuse(Rgb::ONE).two_sided(),
            wo: incident(deg, true),
            alpha: 1.0,
            exact: Some(1.0),
        });
    }
    for kind in KINDS {
        for alpha in ALPHAS {
            for deg in ANGLES {
                // GGX at α = 1 has D = 1/π: at normal incidence the reflected direction
                // makes twice the facet angle, and ρ = ∫₀^{π/4} 2 tan θ cos 2θ dθ = 1 − ln 2.
                let exact = (kind == MicrofacetKind::Ggx && alpha == 1.0 && deg == 0.0).then(|| 1.0 - 2f64.ln());
                v.push(Case {
                    group: Group::Conductor,
                    name: format!("conductor F=1 {kind:?} α={alpha} θ={deg}°"),
                    material: Material::rough_conductor(kind, alpha, eta, k, Rgb::ONE),
                    wo: incident(deg, false),
                    alpha,
                    exact,
                });
                for inside in [false, true] {
                    v.push(Case {
                        group: if inside { Group::DielectricInside } else { Group::DielectricOutside },
                        name: format!("rough dielectric {kind:?} α={alpha} θ={deg}° inside={inside}"),
                        material: Material::rough_dielectric(kind, alpha, 1.5, 1.0, Rgb::ONE, Rgb::ONE),
                        wo: incident(deg, inside),
                        alpha,
                        exact: None,
                    });
                }
            }
            if alpha == 0.1 || alpha == 0.5 {
                for deg in [0.0, 45.0, 89.0] {
                    v.push(Case {
                        group: Group::Plastic,
                        name: format!("rough plastic, white base {kind:?} α={alpha} θ={deg}°"),
                        material: Material::rough_plastic(kind, alpha, 1.49, 1.000277, Rgb::ONE, Rgb::ONE, false),
                        wo: incident(deg, false),
                        alpha,
                        exact: None,
                    });
                }
            }
            v.push(Case {
                group: Group::Conductor,
                name: format!("twosided conductor F=1 back {kind:?} α={alpha} θ=45°"),
                material: Material::rough_conductor(kind, alpha, eta, k, Rgb::ONE).two_sided(),
                wo: incident(45.0, true),
                alpha,
                exact: None,
            });
        }
    }
    // Smooth plastic with a white base and coating: the mirror's F(cos θo) plus the base's
    // (1 − F(cos θo)) (1 − F̄_ext) / (η² (1 − F_dr,int)), F̄_ext the cosine-weighted mean of
    // 1 − F over the hemisphere (quadrature here) and F_dr,int Mitsuba's fit. Physically
    // (1 − F̄_ext) = η² (1 − F_dr,int) and ρ = 1; the fit is within 0.1 % of that.
    for deg in ANGLES {
        let wo = incident(deg, false);
        let eta = 1.49f64 / 1.000277;
        let f_o = fresnel_f64(wo.z as f64, eta);
        let n = 20_000;
        let t_ext: f64 = (0..n).map(|k| (k as f64 + 0.5) / n as f64).map(|mu| (1.0 - fresnel_f64(mu, eta)) * 2.0 * mu / n as f64).sum();
        let exact = f_o + (1.0 - f_o) * t_ext / (eta * eta * (1.0 - mitsuba_fdr(1.0 / eta)));
        v.push(Case {
            group: Group::Plastic,
            name: format!("smooth plastic, white θ={deg}°"),
            material: Material::plastic(1.49, 1.000277, Rgb::ONE, Rgb::ONE, false),
            wo,
            alpha: 0.0,
            exact: Some(exact),
        });
    }
    v
}

/// Mitsuba's fitted diffuse Fresnel reflectance for η < 1 (Egan and Hilgeman), which its
/// `plastic` uses for the internal reflections.
fn mitsuba_fdr(eta: f64) -> f64 {
    assert!(eta < 1.0);
    0.0636 / eta + eta * (eta * -1.4399 + 0.7099) + 0.6681
}

/// Two-sided p-value that `mean` (with standard error `se`) equals `target`, allowing
/// 10⁻⁵ for f32 rounding (white diffuse gives weights 1 − 10⁻⁸ with zero variance).
fn p_equal(mean: f64, se: f64, target: f64) -> f64 {
    let excess = ((mean - target).abs() - 1e-5).max(0.0);
    if excess == 0.0 {
        return 1.0;
    }
    if se == 0.0 {
        return 0.0;
    }
    normal_two_sided_p(excess / se)
}

/// One-sided p-value that `mean` exceeds `bound` by chance.
fn p_not_above(mean: f64, se: f64, bound: f64) -> f64 {
    let excess = mean - bound - 1e-5;
    if excess <= 0.0 {
        return 1.0;
    }
    if se == 0.0 {
        return 0.0;
    }
    0.5 * normal_two_sided_p(excess / se)
}

/// Radiance-mode checks of the smooth dielectric, counted in the same family.
const RADIANCE_CHECKS: usize = 8;

fn significance() -> f64 {
    // Per case: the ≤ 1 test, and one of (exact value, uniform cross-check).
    sidak(0.01, 2 * cases().len() + RADIANCE_CHECKS)
}

fn run_group(group: Group) {
    let significance = significance();
    let mode = TransportMode::Importance;
    for (i, c) in cases().iter().enumerate().filter(|(_, c)| c.group == group) {
        let seed = 0xf00d + i as u64;
        let rho = albedo_by_bsdf_sampling(&c.material, c.wo, mode, seed);
        let (mean, se) = (rho.mean(), rho.std_error());
        // Mitsuba's fitted F_dr puts smooth plastic's exact albedo 0.1 % above 1: the
        // bound is the exact value where one is known above 1.
        let p_le = p_not_above(mean, se, c.exact.unwrap_or(1.0).max(1.0));
        let mut line = format!("{}: ρ = {mean:.4} ± {se:.4} (loss {:.2} %)", c.name, 100.0 * (1.0 - mean));
        assert!(p_le >= significance, "{}: albedo {mean} ± {se} exceeds 1 (p = {p_le:e})", c.name);
        if let Some(exact) = c.exact {
            let p = p_equal(mean, se, exact);
            line += &format!(", exact {exact:.4}, p = {p:.3}");
            assert!(p >= significance, "{}: albedo {mean} ± {se}, expected {exact} (p = {p:e})", c.name);
        } else if c.alpha >= 0.3 {
            let uni = albedo_by_uniform_sampling(&c.material, c.wo, mode, seed);
            let se2 = (se * se + uni.std_error().powi(2)).sqrt();
            let p = p_equal(mean, se2, uni.mean());
            line += &format!(", uniform estimate {:.4} ± {:.4}, p = {p:.3}", uni.mean(), uni.std_error());
            assert!(p >= significance, "{}: BSDF sampling gives {mean} but uniform sampling {} (p = {p:e})", c.name, uni.mean());
        }
        println!("{line}");
    }
}

#[test]
fn furnace_rough_conductors() {
    run_group(Group::Conductor);
}

#[test]
fn furnace_rough_dielectrics_outside() {
    run_group(Group::DielectricOutside);
}

#[test]
fn furnace_rough_dielectrics_inside() {
    run_group(Group::DielectricInside);
}

#[test]
fn furnace_rough_plastic() {
    run_group(Group::Plastic);
}

#[test]
fn furnace_smooth_and_diffuse() {
    run_group(Group::Smooth);
    // Radiance mode: the smooth dielectric's refraction carries 1/η², so
    // ρ = F + (1 − F)/η_it² for η_it = η_t/η_i seen from wo.
    let significance = significance();
    let glass = Material::dielectric(1.5, 1.0, Rgb::ONE, Rgb::ONE);
    let configs = [(0.0, false), (45.0, false), (75.0, false), (89.0, false), (0.0, true), (20.0, true), (40.0, true), (60.0, true)];
    assert_eq!(configs.len(), RADIANCE_CHECKS);
    for (j, (deg, inside)) in configs.into_iter().enumerate() {
        let wo = incident(deg, inside);
        let eta_it: f64 = if inside { 1.0 / 1.5 } else { 1.5 };
        let f = fresnel_f64(wo.z as f64, 1.5);
        let expected = f + (1.0 - f) / (eta_it * eta_it);
        let rho = albedo_by_bsdf_sampling(&glass, wo, TransportMode::Radiance, 0xbeef + j as u64);
        let p = p_equal(rho.mean(), rho.std_error(), expected);
        println!("smooth dielectric Radiance θ={deg}° inside={inside}: ρ = {:.4} ± {:.4}, expected {expected:.4}, p = {p:.3}", rho.mean(), rho.std_error());
        assert!(p >= significance, "Radiance-mode glass θ={deg}° inside={inside}: {} vs {expected} (p = {p:e})", rho.mean());
    }
}
