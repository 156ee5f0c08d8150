//! χ² goodness-of-fit of every light's sampling techniques against their own densities:
//! `sample_li` directions against `pdf_li`, `sample_le` directions against `pdf_le`'s
//! directional part, and emission positions of the lights at infinity on their disk
//! against `pdf_le`'s positional part.
//!
//! Each test was seen to fail once on the injected bug named in its comment (injected,
//! run, reverted). Šidák-corrected over the `TESTS` χ² tests of this file.

use ember_core::light::Light;
use ember_core::math::{Frame, Vec2, Vec3};
use ember_core::rng::SampleStream;
use ember_core::spectrum::Rgb;
use ember_tests::chi2::{Chi2Config, Chi2Result, SphereBinning, chi2_sphere, chi2_square, sidak};

const TESTS: usize = 19;

fn alpha() -> f64 {
    sidak(0.01, TESTS)
}

/// Print the outcome (seen with `--nocapture`), then assert it.
trait Pass {
    fn pass(self);
}
impl Pass for Chi2Result {
    fn pass(self) {
        println!("{}: χ² {:.1} on {} dof, p = {:.3}", self.name, self.statistic, self.dof, self.p_value);
        self.assert_passes(alpha());
    }
}

fn cfg(seed: u64) -> Chi2Config {
    Chi2Config { samples: 500_000, theta_bins: 32, phi_bins: 64, seed }
}

// ---------------------------------------------------------------- scene helpers

const T0: Vec3 = Vec3::new(-1.0, -1.0, 0.0);
const T1: Vec3 = Vec3::new(1.0, -0.5, 0.0);
const T2: Vec3 = Vec3::new(0.2, 1.0, 0.0);

fn triangle(two_sided: bool) -> Light {
    // Winding normal (T1−T0)×(T2−T0) = +z.
    Light::triangle(T0, T1, T2, Rgb::new(1.0, 2.0, 3.0), two_sided)
}

/// Möller–Trumbore in f64: the point where the ray from `o` along `d` meets the triangle.
fn hit_triangle(o: Vec3, d: Vec3) -> Option<Vec3> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let (p0, e1, e2) = (T0.as_dvec3(), (T1 - T0).as_dvec3(), (T2 - T0).as_dvec3());
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det.abs() < 1e-300 {
        return None;
    }
    let tv = o - p0;
    let u = tv.dot(pv) / det;
    let qv = tv.cross(e1);
    let v = d.dot(qv) / det;
    let t = e2.dot(qv) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then(|| (o + t * d).as_vec3())
}

/// The first point where the ray from `o` along unit `d` meets a sphere (from inside: the exit).
fn hit_sphere(o: Vec3, d: Vec3, c: Vec3, r: f32) -> Option<(Vec3, Vec3)> {
    let (o, d, c, r) = (o.as_dvec3(), d.as_dvec3().normalize(), c.as_dvec3(), r as f64);
    let oc = o - c;
    let b = oc.dot(d);
    let disc = b * b - (oc.length_squared() - r * r);
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    let t = if -b - s > 0.0 { -b - s } else { -b + s };
    (t > 0.0).then(|| {
        let p = o + t * d;
        (p.as_vec3(), ((p - c) / r).as_vec3())
    })
}

/// Direction sampler of `sample_li` from `p_ref`.
fn li_dirs(light: Light, p_ref: Vec3) -> impl FnMut(&mut SampleStream) -> Option<Vec3> {
    move |r| light.sample_li(p_ref, r.next_2d()).map(|s| s.wi)
}

// ---------------------------------------------------------------- triangle, sample_li

// Injected bug for the four triangle tests: dropping the cosine in the area → solid-angle
// conversion (`to_solid_angle(1.0, dist2)` in `TriangleLight::pdf_li`) fails each with
// p ≈ 0 (χ² 5.5e4 front, 3.6e5 behind, 4.9e6 close, 7.5e7 grazing).
fn triangle_li(name: &str, two_sided: bool, p_ref: Vec3, binning: SphereBinning, config: Chi2Config) {
    let light = triangle(two_sided);
    let n = Vec3::Z;
    chi2_sphere(name, &config, &binning, li_dirs(light.clone(), p_ref), |w| hit_triangle(p_ref, w).map_or(0.0, |p| light.pdf_li(p_ref, w, p, n).0 as f64))
        .pass();
}

fn toward_centroid(p_ref: Vec3) -> SphereBinning {
    SphereBinning::around((T0 + T1 + T2) / 3.0 - p_ref, 1.0)
}

#[test]
fn triangle_one_sided_in_front() {
    let p_ref = Vec3::new(0.3, 0.2, 1.5);
    triangle_li("triangle one-sided, front", false, p_ref, toward_centroid(p_ref), cfg(1));
}

#[test]
fn triangle_one_sided_behind() {
    // Densities are geometric: the back is sampled (with zero radiance) like the front.
    let p_ref = Vec3::new(-0.4, 0.5, -0.7);
    triangle_li("triangle one-sided, behind", false, p_ref, toward_centroid(p_ref), cfg(2));
}

#[test]
fn triangle_two_sided_close() {
    // Almost the whole hemisphere below the reference point.
    let p_ref = Vec3::new(0.1, 0.0, -0.05);
    triangle_li("triangle two-sided, close", true, p_ref, toward_centroid(p_ref), cfg(3));
}

/// (azimuth about −x, elevation) of a direction: smooth over the grazing band below.
fn az_el(d: Vec3) -> Vec2 {
    let d = d.normalize();
    Vec2::new((-d.y).atan2(-d.x), d.z.clamp(-1.0, 1.0).asin())
}

#[test]
fn triangle_two_sided_grazing() {
    // Beside the triangle, 0.02 above its plane: every direction between 0.27° and 0.51°
    // below the horizon (cos at the light 0.005-0.009). Such a thin band hides between the
    // quadrature points of a spherical binning, so the directions are binned in (azimuth,
    // elevation) over the band's bounding box instead: from p_ref the vertices lie at
    // azimuths 0.359, 0.464, −0.177 (about −x) and horizontal distances 4.27 (T0) to 2.24
    // (T1, the nearest point), so elevations span [−0.0089, −0.0047]. Density on the
    // square: p_ω · cos(el) · Δaz · Δel.
    let p_ref = Vec3::new(3.0, 0.5, 0.02);
    let light = triangle(true);
    let (az0, az1, el0, el1) = (-0.19f32, 0.475f32, -0.0093f32, -0.0045f32);
    let to_square = |d: Vec3| {
        let a = az_el(d);
        Vec2::new((a.x - az0) / (az1 - az0), (a.y - el0) / (el1 - el0))
    };
    let c = Chi2Config { theta_bins: 40, phi_bins: 40, ..cfg(4) };
    chi2_square(
        "triangle two-sided, grazing",
        &c,
        |r| light.sample_li(p_ref, r.next_2d()).map(|s| to_square(s.wi)),
        |q| {
            let (az, el) = (az0 + q.x * (az1 - az0), el0 + q.y * (el1 - el0));
            let w = Vec3::new(-az.cos() * el.cos(), -az.sin() * el.cos(), el.sin());
            hit_triangle(p_ref, w).map_or(0.0, |p| light.pdf_li(p_ref, w, p, Vec3::Z).0 as f64 * (el.cos() * (az1 - az0) * (el1 - el0)) as f64)
        },
    )
    .pass();
}

// ---------------------------------------------------------------- sphere, sample_li

fn sphere_li(name: &str, c: Vec3, r: f32, p_ref: Vec3, concentration: f64, config: Chi2Config) {
    let light = Light::sphere(c, r, Rgb::splat(2.0));
    chi2_sphere(name, &config, &SphereBinning::around(c - p_ref, concentration), li_dirs(light.clone(), p_ref), |w| {
        hit_sphere(p_ref, w, c, r).map_or(0.0, |(p, n)| light.pdf_li(p_ref, w, p, n).0 as f64)
    })
    .pass();
}

// Injected bug: the cone's 1 − cos θ_max written as 1 + cos θ_max (`sin2 / (1.0 -
// safe_sqrt(..))` in sphere.rs `one_minus_cos`) fails this (and `sphere_far_narrow_cone`,
// `sphere_from_its_surface`): the wider sampled cone puts samples off the sphere, where the
// pdf is 0 ("impossible sample").
#[test]
fn sphere_near() {
    sphere_li("sphere near", Vec3::ZERO, 1.0, Vec3::new(0.3, 1.2, 0.9), 1.0, cfg(5));
}

// θ_max ≈ 2·10⁻³ rad: bins concentrated around the centre's direction (θ' = π s⁵, the
// cone spans about 9 of the 32 θ bins). Injected bug: computing 1 − cos θ_max in
// `sample_li` as 1 − √(1 − sin²θ_max), as feeding cos θ_max to `warp::sample_uniform_cone`
// amounts to (f32 cancellation: the sampled cone is about 1 % too wide or narrow), fails
// this with p = 3e-11.
#[test]
fn sphere_far_narrow_cone() {
    let c = Vec3::new(1.0, 2.0, 3.0);
    let p_ref = c + 10.0 * Vec3::new(0.48, -0.6, 0.64);
    sphere_li("sphere far", c, 0.02, p_ref, 5.0, cfg(6));
}

// veach-mis's smallest light (r = 0.05) as its plates see it, 2.4 units away: θ_max ≈ 0.021
// rad; the binning concentrates on the cone, so the silhouette's bins are resolved.
#[test]
fn sphere_small_at_veach_mis_distance() {
    let c = Vec3::new(-28.2792, 3.0, 2.7);
    let p_ref = Vec3::new(-27.8, 0.65, 2.5);
    sphere_li("sphere veach-mis", c, 0.05, p_ref, 5.0, cfg(8));
}

// Injected bug: dropping the cosine at the sphere in `pdf_inside` (`to_solid_angle(1.0, t*t)`)
// fails this with p ≈ 0 (χ² 9.6e4 on 1985 dof).
#[test]
fn sphere_from_inside() {
    sphere_li("sphere inside", Vec3::new(0.5, 0.0, 0.0), 1.5, Vec3::new(1.2, -0.4, 0.6), 1.0, cfg(7));
}

// ---------------------------------------------------------------- emission directions

/// χ² of `sample_le` directions expressed in the frame of the light's normal at the
/// sampled point, against `pdf_le` evaluated at a fixed reference point with normal +z:
/// valid for lights whose directional density is the same at every point.
fn emission_dirs_local(name: &str, light: Light, p_fixed: Vec3, seed: u64) {
    chi2_sphere(
        name,
        &cfg(seed),
        &SphereBinning::uniform(),
        |r| light.sample_le(r.next_2d(), r.next_2d()).map(|s| Frame::from_normal(s.n).to_local(s.dir).normalize()),
        |w| light.pdf_le(p_fixed, Vec3::Z, w).1.0 as f64,
    )
    .pass();
}

// Injected bug: cosine density cos/(2π) instead of cos/π in `TriangleLight::pdf_le`
// (one-sided branch) fails this with p ≈ 0 (∫pdf = 0.5 against all samples produced).
#[test]
fn triangle_one_sided_emission_is_cosine() {
    emission_dirs_local("triangle one-sided emission", triangle(false), T0, 8);
}

// Injected bug: dropping the ½ of the side choice in the two-sided `pdf_le` fails this with
// p ≈ 0 (∫pdf = 2).
#[test]
fn triangle_two_sided_emission_is_cosine_on_both_sides() {
    emission_dirs_local("triangle two-sided emission", triangle(true), T0, 9);
}

// Injected bug: sampling the emission direction with `sample_uniform_hemisphere` in
// `SphereLight::sample_le` (pdf still cosine) fails this with p ≈ 0 (χ² 5.7e5 on 1023 dof).
#[test]
fn sphere_emission_is_cosine() {
    // The sphere's pdf_le reads the normal from the point: the north pole has normal +z.
    let light = Light::sphere(Vec3::new(0.0, 0.0, -1.0), 1.0, Rgb::ONE);
    emission_dirs_local("sphere emission", light, Vec3::ZERO, 10);
}

// Injected bug: `uniform_cone_pdf(.., cos_beam)` instead of the cutoff's cosine in
// `SpotLight::pdf_le` fails this with p ≈ 0 (a third of the samples get density 0 and are
// dropped, while the pdf integrates to 1).
#[test]
fn spot_emission_is_uniform_in_the_cutoff_cone() {
    let pos = Vec3::new(1.0, 2.0, 3.0);
    let axis = Vec3::new(0.3, -1.0, 0.2);
    let light = Light::spot(pos, axis, Rgb::splat(5.0), 35.0, 20.0);
    chi2_sphere(
        "spot emission",
        &cfg(11),
        &SphereBinning::around(axis, 2.0),
        |r| light.sample_le(r.next_2d(), r.next_2d()).map(|s| s.dir),
        |w| light.pdf_le(pos, Vec3::ZERO, w).1.0 as f64,
    )
    .pass();
}

// ---------------------------------------------------------------- lights at infinity

const SCENE_C: Vec3 = Vec3::new(0.5, -1.0, 2.0);
const SCENE_R: f32 = 3.0;

fn environment() -> Light {
    let mut l = Light::constant_environment(Rgb::new(0.5, 1.0, 1.5));
    l.set_scene_bounds(SCENE_C, SCENE_R);
    l
}

// Injected bug: `pdf_li` of the environment returning 1/(2π) fails this with p ≈ 0 (∫pdf = 2).
#[test]
fn environment_li_is_uniform() {
    let light = environment();
    let p_ref = Vec3::new(0.2, 0.1, 0.3);
    chi2_sphere("environment li", &cfg(12), &SphereBinning::uniform(), li_dirs(light.clone(), p_ref), |w| {
        light.pdf_li(p_ref, w, p_ref + w, Vec3::ZERO).0 as f64
    })
    .pass();
}

// Injected bug: `pdf_le`'s direction density 1/(2π) for the environment fails this with
// p ≈ 0 (∫pdf = 2).
#[test]
fn environment_emission_directions_are_uniform() {
    let light = environment();
    chi2_sphere(
        "environment emission dirs",
        &cfg(13),
        &SphereBinning::uniform(),
        |r| light.sample_le(r.next_2d(), r.next_2d()).map(|s| s.dir),
        |w| light.pdf_le(SCENE_C, Vec3::ZERO, w).1.0 as f64,
    )
    .pass();
}

/// Emission positions of a light at infinity, mapped to the square: the disk of radius R
/// across `dir` (checked to lie one radius upstream of the centre), scaled to the unit
/// disk and then to [0,1]². Density on the square: pdf_pos · 4R² inside the disk.
fn disk_positions(name: &str, light: Light, seed: u64) {
    let c = Chi2Config { theta_bins: 40, phi_bins: 40, ..cfg(seed) };
    let along_ok = std::cell::Cell::new(true);
    let res = chi2_square(
        name,
        &c,
        |r| {
            let s = light.sample_le(r.next_2d(), r.next_2d())?;
            let q = s.p - SCENE_C;
            if (q.dot(s.dir) + SCENE_R).abs() > 1e-4 * SCENE_R {
                along_ok.set(false);
            }
            let l = Frame::from_normal(s.dir).to_local(q) / SCENE_R;
            Some(0.5 * (Vec2::new(l.x, l.y) + Vec2::ONE))
        },
        |q| {
            let d = 2.0 * q - Vec2::ONE;
            let dir = Vec3::new(0.36, 0.48, -0.8);
            if d.length_squared() <= 1.0 { (light.pdf_le(SCENE_C, Vec3::ZERO, dir).0.0 * 4.0 * SCENE_R * SCENE_R) as f64 } else { 0.0 }
        },
    );
    assert!(along_ok.get(), "{name}: emission does not start one radius upstream");
    res.pass();
}

// Injected bug: the scene disk's density 1/R² (π dropped in `SceneDisk::pdf`) fails both
// disk tests with p ≈ 0 (∫pdf = π).
#[test]
fn directional_emission_positions_cover_the_scene_disk() {
    let mut light = Light::directional(Vec3::new(0.36, 0.48, -0.8), Rgb::splat(2.0));
    light.set_scene_bounds(SCENE_C, SCENE_R);
    disk_positions("directional emission positions", light, 14);
}

#[test]
fn environment_emission_positions_cover_the_scene_disk() {
    disk_positions("environment emission positions", environment(), 15);
}

// Injected bug (shared with `sphere_near`): 1 + cos θ_max fails this too (impossible
// sample). A reference point 10⁻⁵ r off the sphere: the cone is almost the hemisphere
// above the tangent plane and every sampled point lies right beside p_ref, so the sampled
// direction must come from the cone itself, not from the rounded p − p_ref.
#[test]
fn sphere_from_its_surface() {
    let c = Vec3::ZERO;
    let p_ref = Vec3::new(0.0, 0.6, 0.8) * 1.000_01;
    sphere_li("sphere surface", c, 1.0, p_ref, 1.0, cfg(16));
}

// ---------------------------------------------------------------- environment map

/// A 24 × 12 map: a dim sky brightening toward the zenith, one bright 2 × 1-texel sun,
/// and a black band of rows below the horizon (the density must still cover the texels
/// next to it, which the bilinear lookup reaches), rotated about x and y so that its
/// zenith is not the world's.
fn environment_map() -> Light {
    let (w, h) = (24u32, 12u32);
    let texels: Vec<Rgb> = (0..w * h)
        .map(|k| {
            let (i, j) = (k % w, k / w);
            if (i == 5 || i == 6) && j == 3 {
                Rgb::new(400.0, 300.0, 200.0)
            } else if j >= 8 {
                Rgb::ZERO
            } else {
                Rgb::new(0.2, 0.3, 0.5) * (1.0 + (8 - j) as f32)
            }
        })
        .collect();
    let r = glam::Mat3::from_rotation_y(0.7) * glam::Mat3::from_rotation_x(0.4);
    let mut l = Light::environment_map(w, h, &texels, 1.5, [r.x_axis, r.y_axis, r.z_axis]).expect("a valid map");
    l.set_scene_bounds(SCENE_C, SCENE_R);
    l
}

// Injected bug: the sin θ Jacobian left out of the density (`p_uv / (2π²)`) fails this
// with p ≈ 0 (χ² 1.7e5, ∫pdf 0.79).
#[test]
fn environment_map_li_matches_its_density() {
    let light = environment_map();
    let p_ref = Vec3::new(0.2, 0.1, 0.3);
    chi2_sphere("envmap li", &cfg(21), &SphereBinning::uniform(), li_dirs(light.clone(), p_ref), |w| light.pdf_li(p_ref, w, p_ref + w, Vec3::ZERO).0 as f64)
        .pass();
}

// The same density from emission, where the direction travels away from the sky.
// Injected bug: `pdf_le` reading the density at `dir` instead of `-dir` fails this at
// once (samples in bins of zero density: the black band below the horizon).
#[test]
fn environment_map_emission_directions_match_their_density() {
    let light = environment_map();
    chi2_sphere(
        "envmap emission dirs",
        &cfg(22),
        &SphereBinning::uniform(),
        |r| light.sample_le(r.next_2d(), r.next_2d()).map(|s| s.dir),
        |w| light.pdf_le(SCENE_C, Vec3::ZERO, w).1.0 as f64,
    )
    .pass();
}
