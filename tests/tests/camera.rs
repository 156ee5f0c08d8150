//! The pinhole camera: Mitsuba's pixel mapping (no mirroring or flipping), its field-of-view
//! axes, the film ↔ direction round trip, and the normalisation of importance and of the
//! direction density.

use ember_core::camera::{FovAxis, PerspectiveCamera};
use ember_core::math::{Mat4, Vec2, Vec3};
use ember_core::rng::{SampleStream, Stream};
use ember_core::warp;
use ember_tests::chi2::{Chi2Config, SphereBinning, chi2_sphere, sidak};
use ember_tests::stats::MeanVar;

/// Mitsuba's `Transform4f::look_at`: columns (left, up, dir, origin), left = up × dir.
fn look_at(origin: Vec3, target: Vec3, up: Vec3) -> Mat4 {
    let dir = (target - origin).normalize();
    let left = up.normalize().cross(dir).normalize();
    let new_up = dir.cross(left);
    Mat4::from_cols(left.extend(0.0), new_up.extend(0.0), dir.extend(0.0), origin.extend(1.0))
}

fn tilted() -> Mat4 {
    look_at(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.5, 1.5, -1.0), Vec3::new(0.1, 1.0, 0.0))
}

fn rng(index: u32) -> SampleStream {
    SampleStream::for_sample(0xca3e, Stream::Aux, index, 0, 0)
}

#[test]
fn image_is_neither_mirrored_nor_flipped() {
    let (w, h) = (64, 48);
    // Looking down −z with +y up in a right-handed world, world −x is on the viewer's left.
    let cam = PerspectiveCamera::new(look_at(Vec3::ZERO, -Vec3::Z, Vec3::Y), 60.0, FovAxis::X, w, h);
    let film = |p: Vec3| cam.sample_wi(p, Vec2::ZERO).expect("in view").film;
    assert!(film(Vec3::new(-1.0, 0.0, -5.0)).x < w as f32 / 2.0, "world −x must land in the left half");
    assert!(film(Vec3::new(1.0, 0.0, -5.0)).x > w as f32 / 2.0);
    assert!(film(Vec3::new(0.0, 1.0, -5.0)).y < h as f32 / 2.0, "up must land in the top half");
    assert!(film(Vec3::new(0.0, -1.0, -5.0)).y > h as f32 / 2.0);
    // In camera terms, for any orientation: the camera's +x side is the left of the image.
    let m = tilted();
    let cam = PerspectiveCamera::new(m, 60.0, FovAxis::X, w, h);
    let (x, y) = (m.x_axis.truncate(), m.y_axis.truncate());
    let ahead = cam.position() + 5.0 * cam.forward();
    let f = cam.sample_wi(ahead + x, Vec2::ZERO).unwrap().film;
    assert!(f.x < w as f32 / 2.0 && (f.y - h as f32 / 2.0).abs() < 0.01, "{f}");
    let f = cam.sample_wi(ahead + y, Vec2::ZERO).unwrap().film;
    assert!(f.y < h as f32 / 2.0 && (f.x - w as f32 / 2.0).abs() < 0.01, "{f}");
    // The top-left corner of the film looks toward camera (+x, +y).
    let d = cam.generate_ray(Vec2::ZERO).dir;
    assert!(d.dot(x) > 0.0 && d.dot(y) > 0.0);
    assert!((cam.generate_ray(Vec2::new(w as f32, h as f32) * 0.5).dir - cam.forward()).length() < 1e-6);
}

#[test]
fn film_position_inverts_generate_ray() {
    for (fov, axis, w, h) in [(70.0, FovAxis::X, 96, 64), (30.0, FovAxis::Y, 50, 120), (120.0, FovAxis::Diagonal, 33, 17)] {
        let cam = PerspectiveCamera::new(tilted(), fov, axis, w, h);
        for i in 0..41 {
            for j in 0..37 {
                let film = Vec2::new((i as f32 + 0.37) / 41.0 * w as f32, (j as f32 + 0.61) / 37.0 * h as f32);
                let ray = cam.generate_ray(film);
                assert_eq!(ray.origin, cam.position());
                assert!((ray.dir.length() - 1.0).abs() < 1e-5);
                let back = cam.film_position(ray.dir).expect("on the film");
                assert!((back - film).abs().max_element() < 2e-3 * w.max(h) as f32 / 64.0, "{film} → {back}");
            }
        }
        assert!(cam.film_position(-cam.forward()).is_none());
    }
}

/// Monte Carlo estimate of ∫ f(ω) dω over the cone around `axis` through the film
/// corners given (with a margin), from uniform directions in that cone.
fn integrate_over_cone(axis: Vec3, corners: &[Vec3], n: u32, f: impl Fn(Vec3) -> f64) -> MeanVar {
    let cos_max = corners.iter().map(|c| c.dot(axis)).fold(1.0f32, f32::min);
    let cos_max = (1.0 - 1.5 * (1.0 - cos_max)).max(-1.0); // margin around the region
    let cone_solid_angle = 2.0 * std::f64::consts::PI * (1.0 - cos_max as f64);
    let frame = ember_core::math::Frame::from_normal(axis);
    let mut est = MeanVar::default();
    for k in 0..n {
        let omega = frame.to_world(warp::sample_uniform_cone(rng(k).next_2d(), cos_max));
        est.push(f(omega) * cone_solid_angle);
    }
    est
}

fn film_corners(cam: &PerspectiveCamera) -> [Vec3; 4] {
    let (w, h) = (cam.width() as f32, cam.height() as f32);
    [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)].map(|(a, b)| cam.generate_ray(Vec2::new(a, b)).dir)
}

/// Angle between the forward axis and the ray through a film point, in degrees.
fn angle(cam: &PerspectiveCamera, film: Vec2) -> f32 {
    cam.generate_ray(film).dir.dot(cam.forward()).clamp(-1.0, 1.0).acos().to_degrees()
}

#[test]
fn fov_axes_follow_mitsuba() {
    let m = tilted();
    for (w, h) in [(400u32, 200u32), (150, 300)] {
        let (wf, hf) = (w as f32, h as f32);
        let x_edge = Vec2::new(0.0, hf / 2.0);
        let y_edge = Vec2::new(wf / 2.0, 0.0);
        let cam = |axis| PerspectiveCamera::new(m, 60.0, axis, w, h);
        assert!((angle(&cam(FovAxis::X), x_edge) - 30.0).abs() < 1e-3);
        assert!((angle(&cam(FovAxis::Y), y_edge) - 30.0).abs() < 1e-3);
        assert!((angle(&cam(FovAxis::Diagonal), Vec2::ZERO) - 30.0).abs() < 1e-3);
        let (smaller, larger) = if w > h { (y_edge, x_edge) } else { (x_edge, y_edge) };
        assert!((angle(&cam(FovAxis::Smaller), smaller) - 30.0).abs() < 1e-3);
        assert!((angle(&cam(FovAxis::Larger), larger) - 30.0).abs() < 1e-3);
    }
}

/// ∫_pixel We(ω) cosθ dω = 1 for a centre and a corner pixel of a wide camera, by Monte
/// Carlo over a cone enclosing the pixel, within 4σ; and ∫ We cosθ dω over the whole
/// frustum = W·H.
///
/// Injected bug: cos³θ in place of cos⁴θ in `importance` fails the corner pixel (0, 0) with z ≈ −275.
#[test]
fn importance_integrates_to_one_per_pixel() {
    let (w, h) = (64u32, 48u32);
    let cam = PerspectiveCamera::new(tilted(), 100.0, FovAxis::X, w, h);
    for pixel in [(32u32, 24u32), (0, 0), (63, 20)] {
        let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)].map(|(a, b)| cam.generate_ray(Vec2::new(pixel.0 as f32 + a, pixel.1 as f32 + b)).dir);
        let axis = cam.generate_ray(Vec2::new(pixel.0 as f32 + 0.5, pixel.1 as f32 + 0.5)).dir;
        let est = integrate_over_cone(axis, &corners, 400_000, |omega| {
            let in_pixel = cam.film_position(omega).is_some_and(|f| f.x as u32 == pixel.0 && f.y as u32 == pixel.1);
            if in_pixel { (cam.importance(omega) * omega.dot(cam.forward())) as f64 } else { 0.0 }
        });
        let z = (est.mean() - 1.0) / est.std_error();
        println!("pixel {pixel:?}: ∫ We cos dω = {:.5} ± {:.5} (z = {z:.2})", est.mean(), est.std_error());
        assert!(z.abs() < 4.0, "pixel {pixel:?}: ∫ We cos dω = {} ± {}", est.mean(), est.std_error());
    }
    let est = integrate_over_cone(cam.forward(), &film_corners(&cam), 1_000_000, |omega| (cam.importance(omega) * omega.dot(cam.forward())) as f64);
    let z = (est.mean() - (w * h) as f64) / est.std_error();
    println!("frustum: ∫ We cos dω = {:.2} ± {:.2} vs {} (z = {z:.2})", est.mean(), est.std_error(), w * h);
    assert!(z.abs() < 4.0);
}

/// ∫ pdf_dir dω = 1 over the frustum (Monte Carlo over a cone enclosing it, within 4σ).
///
/// Injected bug: the film area 2·t_x·t_y instead of 4·t_x·t_y (`2.0 /` in `pdf_dir`) fails this with z ≈ 440.
#[test]
fn pdf_dir_integrates_to_one() {
    for (fov, axis, w, h) in [(100.0, FovAxis::X, 64, 48), (20.0, FovAxis::Y, 30, 60)] {
        let cam = PerspectiveCamera::new(tilted(), fov, axis, w, h);
        let est = integrate_over_cone(cam.forward(), &film_corners(&cam), 1_000_000, |omega| cam.pdf_dir(omega).0 as f64);
        let z = (est.mean() - 1.0) / est.std_error();
        println!("fov {fov}: ∫ pdf_dir = {:.5} ± {:.5} (z = {z:.2})", est.mean(), est.std_error());
        assert!(z.abs() < 4.0);
    }
}

/// χ² of the directions of `generate_ray` with the film uniform over the whole film
/// against `pdf_dir`. Injected bug: cos²θ instead of cos³θ in `pdf_dir` fails this with
/// p ≈ 0 (χ² 1.9e5 on 855 dof, ∫pdf 0.75).
#[test]
fn generate_ray_directions_match_pdf_dir() {
    let (w, h) = (80u32, 50u32);
    let cam = PerspectiveCamera::new(tilted(), 110.0, FovAxis::X, w, h);
    let cfg = Chi2Config { samples: 500_000, theta_bins: 32, phi_bins: 64, seed: 3 };
    let res = chi2_sphere(
        "camera directions",
        &cfg,
        &SphereBinning::around(cam.forward(), 1.5),
        |r| {
            let u = r.next_2d();
            Some(cam.generate_ray(u * Vec2::new(w as f32, h as f32)).dir)
        },
        |d| cam.pdf_dir(d).0 as f64,
    );
    println!("{}: χ² {:.1} on {} dof, p = {:.3}", res.name, res.statistic, res.dof, res.p_value);
    res.assert_passes(sidak(0.01, 1));
}

#[test]
fn sample_wi_connects_to_the_pinhole() {
    let (w, h) = (64u32, 48u32);
    let cam = PerspectiveCamera::new(tilted(), 70.0, FovAxis::X, w, h);
    let mut hits = 0;
    for k in 0..20_000 {
        let mut r = rng(k);
        let p = cam.position() + Vec3::new(r.next_f32() - 0.5, r.next_f32() - 0.5, r.next_f32() - 0.5) * 20.0;
        let dir = (p - cam.position()).normalize();
        match cam.sample_wi(p, Vec2::ZERO) {
            Some(s) => {
                hits += 1;
                assert!((s.wi + dir).length() < 1e-5);
                assert!((s.dist - (p - cam.position()).length()).abs() < 1e-4 * s.dist);
                assert_eq!(s.importance, cam.importance(-s.wi));
                assert!(s.importance > 0.0 && s.pdf.0 == 1.0);
                assert_eq!(Some(s.film), cam.film_position(-s.wi));
                // The pixel that a primary ray through s.film reaches points back at p.
                assert!(cam.generate_ray(s.film).dir.dot(dir) > 0.99999);
            }
            None => assert!(cam.film_position(dir).is_none() || cam.importance(dir) == 0.0),
        }
    }
    assert!(hits > 1000, "{hits}");
    // Behind the camera, and at the pinhole: nothing.
    assert!(cam.sample_wi(cam.position() - cam.forward(), Vec2::ZERO).is_none());
    assert!(cam.sample_wi(cam.position(), Vec2::ZERO).is_none());
    assert_eq!(cam.importance(-cam.forward()), 0.0);
    assert_eq!(cam.pdf_dir(-cam.forward()).0, 0.0);
    assert_eq!((cam.width(), cam.height()), (w, h));
}

/// Degenerate construction: zero size, singular transform, extreme fov: no panic, no NaN.
#[test]
fn degenerate_camera_is_finite() {
    for (m, fov, w, h) in [(Mat4::ZERO, 60.0, 0, 0), (tilted(), 0.0, 10, 10), (tilted(), 180.0, 10, 1), (Mat4::IDENTITY, -5.0, 1, 1)] {
        let cam = PerspectiveCamera::new(m, fov, FovAxis::Diagonal, w, h);
        let ray = cam.generate_ray(Vec2::new(0.5, 0.5));
        assert!(ray.dir.is_finite() && ray.origin.is_finite());
        assert!(cam.importance(ray.dir).is_finite() && cam.pdf_dir(ray.dir).0.is_finite());
        if let Some(s) = cam.sample_wi(cam.position() + ray.dir, Vec2::ZERO) {
            assert!(s.importance.is_finite() && s.film.is_finite());
        }
    }
}
