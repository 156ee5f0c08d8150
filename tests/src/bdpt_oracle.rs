//! An f64 oracle for balance-heuristic weights of bidirectional strategies, independent
//! of the BDPT vertex code: it calls only the primitive densities (light emission,
//! camera, BSDF) and converts them to area measure itself. Shared by the BDPT, LVCBPT
//! and SPCBPT weight tests (`tests/tests/{bdpt,lvcbpt,spcbpt}_mis.rs`).
//!
//! For a full path x₀ (light end) … x_{n−1} (camera), strategy s builds x₀…x_{s−1} from
//! the light and x_s…x_{n−1} from the camera; its density is the product of the
//! per-vertex densities of both sub-paths. A Dirac vertex contributes the unit Dirac in
//! solid angle once to every strategy able to produce the path, so that symbol cancels
//! (taken as 1); its conversion to area, cos/d² of the segment it samples, stays.

use ember_core::bsdf::TransportMode;
use ember_core::math::Frame;
use ember_core::measure::VertexPdf;
use ember_core::path::{Vertex, VertexKind};
use ember_core::scene::Scene;
use glam::Vec3;

/// Density (f64, per unit area at `to`) of sampling `to` from `from`, which was reached
/// from `prev` (None for endpoints), by a walk in `mode`: `Radiance` from the camera
/// side (`to` lies toward the light), `Importance` from the light side. Independent of the
/// BDPT vertex code. On segment paths (segment BDPT) the segment between camera-side `a`
/// and light-side `b` runs from `a.exit` to `b.p`; on vertex paths `exit` is `p`.
pub fn area_density(scene: &Scene, prev: Option<&Vertex>, from: &Vertex, to: &Vertex, mode: TransportMode) -> f64 {
    let (start, end, n_end) = match mode {
        TransportMode::Radiance => (from.exit.p, to.p, to.ng),
        TransportMode::Importance => (from.p, to.exit.p, to.exit.ng),
    };
    let d = end - start;
    let d2 = d.length_squared() as f64;
    let w = d.normalize();
    let cos_to = if to.ng == Vec3::ZERO { 1.0 } else { n_end.dot(w).abs() as f64 };
    let solid_angle = match from.kind {
        VertexKind::Camera => scene.camera.pdf_dir(w).0 as f64,
        VertexKind::Light(id) => scene.lights[id as usize].pdf_le(from.p, from.ng, w).1.0 as f64,
        VertexKind::Surface if prev.is_none() => {
            // A surface emitter as the light-path origin.
            let id = from.emitter.expect("light origin must emit");
            scene.lights[id as usize].pdf_le(from.p, from.ng, w).1.0 as f64
        }
        VertexKind::Surface => {
            let m = &scene.materials[from.material as usize];
            if m.is_delta() {
                // Dirac: the unit Dirac in solid angle, the same symbolic factor once per
                // specular vertex in every strategy; its area conversion stays.
                return cos_to / d2;
            }
            let frame = Frame::from_normal(from.frame.n);
            let prev = prev.unwrap();
            let wp = match mode {
                TransportMode::Radiance => (prev.exit.p - from.p).normalize(),
                TransportMode::Importance => (prev.p - from.exit.p).normalize(),
            };
            m.pdf(frame.to_local(wp), frame.to_local(w), TransportMode::Radiance).0 as f64
        }
        VertexKind::InfiniteLight => unreachable!("no infinite lights in this scene"),
    };
    solid_angle * cos_to / d2
}

/// The disk kernel's density (f64, per unit area at `sample`) of drawing `sample` around
/// `center` (normals `n_sample`, `n_center`), radius `r`: |n_s·n_c| / (π r²) within the
/// tangent disk and r of the tangent plane. Written here from the definition, apart from
/// `ember_core::segment::Kernel`.
pub fn disk_kernel_density(r: f64, center: Vec3, n_center: Vec3, sample: Vec3, n_sample: Vec3) -> f64 {
    let (c, n, x) = (center.as_dvec3(), n_center.as_dvec3().normalize(), sample.as_dvec3());
    let d = x - c;
    let h = d.dot(n);
    if (d - n * h).length_squared() >= r * r || h.abs() > r {
        return 0.0;
    }
    n_sample.as_dvec3().normalize().dot(n).abs() / (std::f64::consts::PI * r * r)
}

/// The kernel density with which junction `v` was drawn from the camera side (the exit
/// around the hit, `toward_light`) or the light side (the shading point around the exit);
/// 1 where the junction did not move (the Dirac kernel, the kernel's miss mass).
fn junction_density(radius: Option<f64>, v: &Vertex, camera_side: bool) -> f64 {
    match radius {
        Some(r) if v.exit.p != v.p => {
            if camera_side {
                disk_kernel_density(r, v.p, v.ng, v.exit.p, v.exit.ng)
            } else {
                disk_kernel_density(r, v.exit.p, v.exit.ng, v.p, v.ng)
            }
        }
        _ => 1.0,
    }
}

pub fn origin_density(scene: &Scene, x0: &Vertex) -> f64 {
    let id = match x0.kind {
        VertexKind::Light(id) => id,
        _ => x0.emitter.expect("x0 emits"),
    };
    let light = &scene.lights[id as usize];
    let pos = if light.is_delta() { 1.0 } else { light.pdf_le(x0.p, x0.ng, x0.ng).0.0 as f64 };
    scene.light_pmf(id) as f64 * pos
}

pub fn is_delta_surface(scene: &Scene, v: &Vertex) -> bool {
    v.kind == VertexKind::Surface && scene.materials[v.material as usize].is_delta()
}

/// Balance weights n_s p_s / Σ n_i p_i of every strategy s (index = s) for full path `x`,
/// with the sample count `count(s, t)` of each strategy; `None` where a strategy cannot
/// produce the path.
pub fn brute_force_weights(scene: &Scene, x: &[Vertex], count: impl Fn(usize, usize) -> f64) -> Vec<Option<f64>> {
    brute_force_segment_weights(scene, x, None, count)
}

/// [`brute_force_weights`] of a segment path whose junctions a disk kernel of radius
/// `radius` moved (segment BDPT): each sub-path vertex also carries the kernel density of
/// the point its side drew around the one it reached (the light end has no junction).
pub fn brute_force_segment_weights(scene: &Scene, x: &[Vertex], radius: Option<f64>, count: impl Fn(usize, usize) -> f64) -> Vec<Option<f64>> {
    let n = x.len();
    let mut p = vec![None; n + 1];
    if n == 2 {
        p[0] = Some(1.0);
        return p;
    }
    for s in 0..n {
        let t = n - s;
        if !strategy_can_produce(scene, x, s) || t == 0 {
            continue;
        }
        let mut prod = 1.0f64;
        for i in 0..s {
            prod *= match i {
                0 => origin_density(scene, &x[0]),
                1 => area_density(scene, None, &x[0], &x[1], TransportMode::Importance),
                _ => area_density(scene, Some(&x[i - 2]), &x[i - 1], &x[i], TransportMode::Importance),
            };
            if i > 0 {
                prod *= junction_density(radius, &x[i], false);
            }
        }
        for j in 0..t {
            let k = n - 1 - j;
            prod *= match j {
                0 => 1.0,
                1 => area_density(scene, None, &x[n - 1], &x[k], TransportMode::Radiance),
                _ => area_density(scene, Some(&x[k + 2]), &x[k + 1], &x[k], TransportMode::Radiance),
            };
            if j > 0 && k > 0 {
                prod *= junction_density(radius, &x[k], true);
            }
        }
        p[s] = Some(prod * count(s, t));
    }
    let total: f64 = p.iter().flatten().sum();
    p.iter().map(|v| v.map(|v| v / total)).collect()
}

/// The full path, light end first, of strategy (s, t) joining `light[..s]` and `cam[..t]`,
/// with the endpoint `sampled` at connection time (the light point of s = 1, the camera
/// of t = 1) in place of the sub-path's own; `None` where the camera path escaped to an
/// infinite light (the brute force has none).
pub fn full_path(light: &[Vertex], cam: &[Vertex], s: usize, t: usize, sampled: Option<Vertex>) -> Option<Vec<Vertex>> {
    let mut x: Vec<Vertex> = light[..s].to_vec();
    let mut cpart: Vec<Vertex> = cam[..t].to_vec();
    if let Some(v) = sampled {
        if s == 1 { x[0] = v } else { cpart[0] = v }
    }
    if cpart.last()?.kind == VertexKind::InfiniteLight {
        return None;
    }
    cpart.reverse();
    x.extend(cpart);
    Some(x)
}

/// Can strategy s (light prefix x₀…x_{s−1}, camera suffix x_s…) produce full path `x`?
/// s = 0 needs x₀ to emit and not be a Dirac light; otherwise x_{s−1} and x_s are joined by a connection, which
/// neither may be Dirac for.
pub fn strategy_can_produce(scene: &Scene, x: &[Vertex], s: usize) -> bool {
    if s == 0 {
        // Emission hits reach neither a point or spot light's position nor a directional light.
        let hittable = match x[0].kind {
            VertexKind::Light(id) => !scene.lights[id as usize].is_delta(),
            _ => true,
        };
        x[0].kind != VertexKind::Camera && x[0].emitter.is_some() && hittable
    } else {
        !is_delta_surface(scene, &x[s - 1]) && !is_delta_surface(scene, &x[s])
    }
}

/// The sub-paths strategy (s, n − s) would have generated for full path `x`, with their
/// densities filled in as the random walk fills them.
pub fn split(scene: &Scene, x: &[Vertex], s: usize) -> (Vec<Vertex>, Vec<Vertex>) {
    let mut light: Vec<Vertex> = x[..s].to_vec();
    let mut cam: Vec<Vertex> = x[s..].iter().rev().copied().collect();
    for (path, mode) in [(&mut light, TransportMode::Importance), (&mut cam, TransportMode::Radiance)] {
        for i in 0..path.len() {
            path[i].pdf_rev = VertexPdf::ZERO;
            path[i].pdf_fwd = match i {
                0 if path[0].kind == VertexKind::Camera => VertexPdf::ZERO,
                0 => path.get(1).or(x.get(1)).map_or(VertexPdf::ZERO, |next| path[0].pdf_light_origin(scene, next)),
                1 => path[0].pdf(scene, None, &path[1], mode),
                _ => path[i - 1].pdf(scene, Some(&path[i - 2]), &path[i], mode),
            };
            if i + 2 < path.len() {
                path[i].pdf_rev = path[i + 1].pdf(scene, Some(&path[i + 2]), &path[i], mode.flip());
            }
        }
    }
    (light, cam)
}

/// Calls `f(s, t, light, camera)` for every strategy BDPT uses that can produce full path
/// `x` ((1, 1) is not used: (0, 2) sees emitters directly), with the sub-paths that
/// strategy would have generated ([`split`]).
pub fn for_each_strategy_split(scene: &Scene, x: &[Vertex], mut f: impl FnMut(usize, usize, &[Vertex], &[Vertex])) {
    let n = x.len();
    for s in 0..n {
        let t = n - s;
        if !strategy_can_produce(scene, x, s) || (s == 1 && t == 1) {
            continue;
        }
        let (light, camera) = split(scene, x, s);
        f(s, t, &light, &camera);
    }
}

/// Density (f64) with which the camera side generates x_i of full path `x` (i < n − 1).
fn camera_side_density(scene: &Scene, x: &[Vertex], i: usize) -> f64 {
    let n = x.len();
    if i + 1 == n - 1 {
        area_density(scene, None, &x[n - 1], &x[i], TransportMode::Radiance)
    } else {
        area_density(scene, Some(&x[i + 2]), &x[i + 1], &x[i], TransportMode::Radiance)
    }
}

/// Density (f64) with which the light side generates x_i.
fn light_side_density(scene: &Scene, x: &[Vertex], i: usize) -> f64 {
    match i {
        0 => origin_density(scene, &x[0]),
        1 => area_density(scene, None, &x[0], &x[1], TransportMode::Importance),
        _ => area_density(scene, Some(&x[i - 2]), &x[i - 1], &x[i], TransportMode::Importance),
    }
}

/// VCM's balance weights for full path `x`: connection techniques (index s, counts
/// `count(s, t)`) and merges at each x_j (index j; density η · p_{j+1} · p←(x_j), where
/// p_{j+1} is the formal product of technique j + 1's densities even where that
/// connection is impossible). `None` where a technique cannot produce the path.
pub fn brute_force_vcm_weights(scene: &Scene, x: &[Vertex], count: impl Fn(usize, usize) -> f64, eta: f64) -> (Vec<Option<f64>>, Vec<Option<f64>>) {
    let n = x.len();
    let mut conn = vec![None; n + 1];
    let mut merge = vec![None; n];
    if n == 2 {
        conn[0] = Some(1.0);
        return (conn, merge);
    }
    let fwd: Vec<f64> = (0..n - 1).map(|i| light_side_density(scene, x, i)).collect();
    let rev: Vec<f64> = (0..n - 1).map(|i| camera_side_density(scene, x, i)).collect();
    let product = |s: usize| -> f64 { (0..s).map(|i| fwd[i]).product::<f64>() * (s..n - 1).map(|i| rev[i]).product::<f64>() };
    for s in 0..n {
        if strategy_can_produce(scene, x, s) && !(s == 1 && n == 2) {
            conn[s] = Some(product(s) * count(s, n - s));
        }
    }
    for j in 1..n - 1 {
        let v = &x[j];
        if v.kind == VertexKind::Surface && !is_delta_surface(scene, v) {
            merge[j] = Some(eta * product(j + 1) * rev[j]);
        }
    }
    let total: f64 = conn.iter().chain(merge.iter()).flatten().sum();
    (conn.iter().map(|v| v.map(|v| v / total)).collect(), merge.iter().map(|v| v.map(|v| v / total)).collect())
}
