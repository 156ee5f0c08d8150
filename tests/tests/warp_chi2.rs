//! χ² goodness-of-fit of every warp in `ember_core::warp` against its own pdf.
//!
//! Injected-bug check (done once, reverted): making `cosine_hemisphere_pdf` return
//! cos θ/(2π) fails `cosine_hemisphere` with p ≈ 0 (and the ∫pdf = 0.5 ≠ sampled 1.0 bin);
//! sampling the cone with (1 + cos_max) in place of (1 − cos_max) fails `cone_wide` with p ≈ 0 (the first cone checked).

use ember_core::math::Vec2;
use ember_core::warp::*;
use ember_tests::chi2::{Chi2Config, SphereBinning, chi2_sphere, chi2_square, sidak};
use glam::Vec3;

const TESTS: usize = 9;

fn cfg() -> Chi2Config {
    Chi2Config { samples: 400_000, theta_bins: 32, phi_bins: 64, seed: 11 }
}

#[test]
fn hemisphere_sphere_and_cone_warps_match_their_pdfs() {
    let alpha = sidak(0.01, TESTS);
    let c = cfg();
    chi2_sphere("uniform_hemisphere", &c, &SphereBinning::uniform(), |r| Some(sample_uniform_hemisphere(r.next_2d())), |w| uniform_hemisphere_pdf(w).0 as f64)
        .assert_passes(alpha);
    chi2_sphere("cosine_hemisphere", &c, &SphereBinning::uniform(), |r| Some(sample_cosine_hemisphere(r.next_2d())), |w| cosine_hemisphere_pdf(w).0 as f64)
        .assert_passes(alpha);
    chi2_sphere("uniform_sphere", &c, &SphereBinning::uniform(), |r| Some(sample_uniform_sphere(r.next_2d())), |_| uniform_sphere_pdf().0 as f64)
        .assert_passes(alpha);
    for (name, cos_max, conc) in [("cone_wide", -0.3f32, 1.0), ("cone_mid", 0.8, 2.0), ("cone_narrow", 0.9999, 3.0)] {
        chi2_sphere(
            name,
            &c,
            &SphereBinning::around(Vec3::Z, conc),
            |r| Some(sample_uniform_cone(r.next_2d(), cos_max)),
            |w| uniform_cone_pdf(w, cos_max).0 as f64,
        )
        .assert_passes(alpha);
    }
}

#[test]
fn planar_warps_match_their_pdfs() {
    let alpha = sidak(0.01, TESTS);
    let c = Chi2Config { theta_bins: 40, phi_bins: 40, ..cfg() };
    // Disk [-1,1]² mapped to the unit square: density on the square = 4 · (1/π) inside the disk.
    chi2_square(
        "concentric_disk",
        &c,
        |r| Some(0.5 * (sample_concentric_disk(r.next_2d()) + Vec2::ONE)),
        |q| 4.0 * concentric_disk_pdf(2.0 * q - Vec2::ONE).0 as f64,
    )
    .assert_passes(alpha);
    // Barycentrics (b0, b1) live in the lower-left half of the square; density 2 there
    // (uniform on a triangle of area 1/2).
    chi2_square(
        "triangle",
        &c,
        |r| Some(sample_uniform_triangle(r.next_2d())),
        |b| {
            if b.x + b.y <= 1.0 { 0.5 * uniform_triangle_pdf(0.5).0 as f64 * 2.0 } else { 0.0 }
        },
    )
    .assert_passes(alpha);
}
