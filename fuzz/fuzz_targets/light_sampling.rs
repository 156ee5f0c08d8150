//! Light sampling invariants for arbitrary finite geometry at scales 1e-4 … 1e5, any
//! emission from 1e-8 to 1e8, and arbitrary random numbers (issue 8):
//! - `sample_li` returns `None` or a unit `wi`, a positive distance, finite non-negative
//!   radiance and a finite `pdf > 0`, which for non-delta lights equals
//!   `pdf_li(p_ref, wi, p, n)` within 1 %;
//! - `sample_le` returns `None` or a finite origin, a unit direction, finite non-negative
//!   radiance and finite positive densities equal to `pdf_le(p, n, dir)` (the non-delta
//!   components) within 1 % (the direction density also within 1e-6 absolute: for
//!   grazing emission f32 recomputes cos θ only to ~1e-8, found by this target);
//! - `power` is finite and non-negative; `pdf_li` / `pdf_le` at arbitrary arguments are
//!   finite and non-negative;
//! - at least 40 % of inputs produce an emission sample (the target cannot pass by
//!   rejecting everything; only degenerate triangles and zero-radius spheres may refuse).
#![no_main]

use ember_core::light::Light;
use ember_core::spectrum::Rgb;
use ember_fuzz::{Bytes, ShareFloor, close, finite_nonneg3};
use glam::Vec3;
use libfuzzer_sys::fuzz_target;

static EMITTED: ShareFloor = ShareFloor::new("light_sampling (sample_le)", 0.4, 4096);

fn light(b: &mut Bytes) -> Light {
    let radiance = Rgb::new(b.log_uniform(1e-8, 1e8), b.log_uniform(1e-8, 1e8), b.unit());
    match b.u8() % 6 {
        0 => {
            let base = b.point();
            let size = b.log_uniform(1e-4, 1e4);
            let mut corner = || base + b.direction().unwrap_or(Vec3::Y) * size;
            Light::triangle(corner(), corner(), corner(), radiance, b.u8() & 1 == 1)
        }
        1 => Light::sphere(b.point(), b.log_uniform(1e-4, 1e4), radiance),
        2 => Light::point(b.point(), radiance),
        3 => Light::spot(b.point(), b.direction().unwrap_or(Vec3::Z), radiance, b.finite(), b.finite()),
        4 => Light::directional(b.direction().unwrap_or(Vec3::Z), radiance),
        _ => Light::constant_environment(radiance),
    }
}

fn finite_nonneg(p: f32) -> bool {
    p.is_finite() && p >= 0.0
}

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes::new(data);
    let mut l = light(&mut b);
    l.set_scene_bounds(b.point(), b.log_uniform(1e-3, 1e5));
    let p_ref = b.point();
    let (u, u_pos, u_dir) = (b.unit2(), b.unit2(), b.unit2());
    let Some(w_any) = b.direction() else { return };

    assert!(finite_nonneg(l.power()), "power {} of {l:?}", l.power());
    let (pa, pd) = l.pdf_le(p_ref, w_any, w_any);
    assert!(finite_nonneg(pa.value()) && finite_nonneg(pd.value()), "pdf_le {pa:?} {pd:?} of {l:?}");
    assert!(finite_nonneg(l.pdf_li(p_ref, w_any, p_ref + w_any, w_any).value()), "pdf_li of {l:?}");
    assert!(finite_nonneg3(l.radiance(p_ref, w_any, w_any).to_array()), "radiance of {l:?}");

    if let Some(s) = l.sample_li(p_ref, u) {
        let ctx = || format!("{l:?}, p_ref {p_ref:?}, u {u:?}, sample {s:?}");
        assert!(s.wi.is_finite() && (s.wi.length() - 1.0).abs() < 1e-4, "wi: {}", ctx());
        assert!(s.dist > 0.0 && !s.dist.is_nan(), "dist: {}", ctx());
        assert!(finite_nonneg3(s.radiance.to_array()), "radiance: {}", ctx());
        assert!(s.pdf.value().is_finite() && s.pdf.value() > 0.0, "pdf: {}", ctx());
        if !s.is_delta {
            let pdf = l.pdf_li(p_ref, s.wi, s.p, s.n).value();
            assert!(close(pdf, s.pdf.value(), 1e-2, 0.0), "pdf_li = {pdf}: {}", ctx());
        }
    }

    let e = l.sample_le(u_pos, u_dir);
    EMITTED.record(e.is_some());
    if let Some(e) = e {
        let ctx = || format!("{l:?}, u_pos {u_pos:?}, u_dir {u_dir:?}, sample {e:?}");
        assert!(e.p.is_finite() && e.n.is_finite(), "p/n: {}", ctx());
        assert!(e.dir.is_finite() && (e.dir.length() - 1.0).abs() < 1e-4, "dir: {}", ctx());
        assert!(finite_nonneg3(e.radiance.to_array()), "radiance: {}", ctx());
        assert!(e.pdf_pos.value().is_finite() && e.pdf_pos.value() > 0.0, "pdf_pos: {}", ctx());
        assert!(e.pdf_dir.value().is_finite() && e.pdf_dir.value() > 0.0, "pdf_dir: {}", ctx());
        let (pos, dir) = l.pdf_le(e.p, e.n, e.dir);
        if !e.delta_pos {
            assert!(close(pos.value(), e.pdf_pos.value(), 1e-2, 0.0), "pdf_le pos = {pos:?}: {}", ctx());
        }
        if !e.delta_dir {
            assert!(close(dir.value(), e.pdf_dir.value(), 1e-2, 1e-6), "pdf_le dir = {dir:?}: {}", ctx());
        }
    }
});
