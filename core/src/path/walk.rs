//! Generation of the camera and light sub-paths (pbrt-v3's `RandomWalk`).

use heapless::Vec as FixedVec;

use super::MAX_VERTICES;
use super::vertex::{Exit, Vertex, VertexKind, infinite_light_density};
use crate::bsdf::TransportMode;
use crate::camera::PrimaryRay;
use crate::geometry::{Ray, RayQuery, spawn_ray};
use crate::math::{Vec2, Vec3};
use crate::measure::{AreaPdf, VertexPdf};
use crate::rng::SampleStream;
use crate::scene::Scene;
use crate::segment::Junctions;
use crate::spectrum::Rgb;
use crate::transport::walk::{Layout, Leave, PathState, Roulette, Walk};
use crate::transport::{Counters, RenderParams, SurfacePoint, light_roulette_reference};

/// A sub-path: vertices in the order they were generated.
pub type SubPath = FixedVec<Vertex, MAX_VERTICES>;

/// The sub-path walks' random dimensions: 4 per bounce (lobe 1, direction 2, roulette 1).
const LAYOUT: Layout = Layout { per_bounce: 4, light: 0, lobe: 0, roulette: 3 };

/// Camera sub-path through continuous film position `film`, at most `max_vertices`
/// vertices including the camera.
pub fn camera_subpath<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    film: Vec2,
    max_vertices: usize,
    rng: &mut SampleStream,
    counters: &mut Counters,
) -> SubPath {
    camera_subpath_with_kernel(scene, tracer, params, film, max_vertices, rng, None, counters)
}

/// [`camera_subpath`] with the kernel of `junctions` moving each vertex's exit (segment
/// BDPT, [`crate::estimators::segment::sbdpt`]); `None` is the Dirac kernel.
pub fn camera_subpath_with_kernel<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    film: Vec2,
    max_vertices: usize,
    rng: &mut SampleStream,
    junctions: Option<&mut Junctions>,
    counters: &mut Counters,
) -> SubPath {
    if max_vertices == 0 {
        return SubPath::new();
    }
    let u_lens = scene.camera.lens_u(rng);
    let primary = PrimaryRay { ray: scene.camera.generate_ray_lens(film, u_lens), film };
    camera_subpath_from(scene, tracer, params, Some(primary), max_vertices, rng, junctions, counters)
}

/// Camera sub-path from a drawn primary ray, its throughput starting at 1 (the film
/// applies the pixel filter); `None` (no primary ray) leaves only the camera vertex, so the
/// t = 1 strategies, which replace it, still run.
#[allow(clippy::too_many_arguments)]
pub fn camera_subpath_from<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    primary: Option<PrimaryRay>,
    max_vertices: usize,
    rng: &mut SampleStream,
    junctions: Option<&mut Junctions>,
    counters: &mut Counters,
) -> SubPath {
    let mut path = SubPath::new();
    if max_vertices == 0 {
        return path;
    }
    let Some(primary) = primary else {
        let _ = path.push(Vertex::camera(scene.camera.position(), Rgb::ZERO));
        return path;
    };
    let ray = primary.ray;
    let beta = Rgb::ONE;
    let _ = path.push(Vertex::camera(ray.origin, beta));
    random_walk(scene, tracer, params, ray, beta, max_vertices, TransportMode::Radiance, rng, junctions, counters, &mut path);
    path
}

/// Light sub-path with at most `max_vertices` vertices including the light.
pub fn light_subpath<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    max_vertices: usize,
    rng: &mut SampleStream,
    counters: &mut Counters,
) -> SubPath {
    light_subpath_with_kernel(scene, tracer, params, max_vertices, rng, None, counters)
}

/// [`light_subpath`] with the kernel of `junctions` moving each vertex's shading point
/// away from the hit (segment BDPT); `None` is the Dirac kernel.
pub fn light_subpath_with_kernel<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    max_vertices: usize,
    rng: &mut SampleStream,
    mut junctions: Option<&mut Junctions>,
    counters: &mut Counters,
) -> SubPath {
    let mut path = SubPath::new();
    let (u_light, u_pos, u_dir) = (rng.next_f32(), rng.next_2d(), rng.next_2d());
    if max_vertices == 0 {
        return path;
    }
    let Some(table) = scene.light_selection.as_ref() else { return path };
    let chosen = table.sample(u_light);
    let id = chosen.index as u32;
    let light = &scene.lights[chosen.index];
    let Some(es) = light.sample_le(u_pos, u_dir) else { return path };
    let pdf_pos = if es.delta_pos { 1.0 } else { es.pdf_pos.0 };
    if !(pdf_pos > 0.0) || !es.pdf_dir.is_positive() || es.radiance.is_black() {
        return path;
    }
    let cos0 = if es.n == Vec3::ZERO { 1.0 } else { es.n.dot(es.dir).abs() };
    let beta = es.radiance * (cos0 / (chosen.pmf * pdf_pos * es.pdf_dir.0));
    let ray = if es.n == Vec3::ZERO { Ray::new(es.p, es.dir, f32::INFINITY) } else { spawn_ray(es.p, es.n, es.dir) };
    if light.is_infinite() {
        let mut v0 = Vertex::infinite(es.p - es.dir, es.radiance, VertexPdf::of_direction(infinite_light_density(scene, -es.dir)));
        v0.delta = light.is_delta();
        let _ = path.push(v0);
        random_walk(scene, tracer, params, ray, beta, max_vertices, TransportMode::Importance, rng, junctions.as_deref_mut(), counters, &mut path);
        // The second vertex's forward density is the disk's position density, per area
        // at the point the ray reached (its exit, which a light walk's kernel leaves).
        if let Some(v1) = path.get_mut(1) {
            v1.pdf_fwd = VertexPdf::at_point(AreaPdf(pdf_pos * if v1.is_on_surface() { v1.exit.ng.dot(es.dir).abs() } else { 1.0 }));
        }
    } else {
        // A point or spot light's position is a Dirac: its origin density is the
        // selection probability alone.
        let origin = if es.delta_pos { VertexPdf::discrete(chosen.pmf) } else { VertexPdf::at_point(es.pdf_pos * chosen.pmf) };
        let _ = path.push(Vertex::light(id, es.p, es.n, es.radiance, origin, light.is_delta()));
        random_walk(scene, tracer, params, ray, beta, max_vertices, TransportMode::Importance, rng, junctions, counters, &mut path);
    }
    path
}

/// Extend `path` by sampling BSDFs from `ray` until `max_vertices`, absorption,
/// escape or Russian roulette: the one walk ([`crate::transport::walk`]), each vertex
/// stored with its densities.
///
/// Forward and reverse densities are evaluated from the stored vertex positions, not
/// taken from the sampler: the ray left from an offset origin, so near corners the
/// sampled direction and the direction between stored vertices differ by up to a few
/// percent in density. Evaluating every strategy's densities from the same positions
/// makes the balance weights of one path sum to one exactly (pbrt-v3 mixes the two).
///
/// With `junctions` every surface vertex is a junction of two segments: a camera walk
/// (radiance) keeps the BSDF at the hit and starts the next segment at the kernel's
/// sample (`exit`); a light walk (importance) keeps the hit as `exit` and moves the
/// shading point, BSDF and frame to the kernel's sample (`p`), as segment PT and LT do.
/// The kernel is drawn at every vertex, the last one included, since connections start
/// from it; its random numbers come from the junctions' own stream.
fn random_walk<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    ray: Ray,
    beta: Rgb,
    max_vertices: usize,
    mode: TransportMode,
    rng: &mut SampleStream,
    mut junctions: Option<&mut Junctions>,
    counters: &mut Counters,
    path: &mut SubPath,
) {
    let walk = Walk { mode, layout: LAYOUT };
    // Bounce k (the path's (k + 1)-th vertex) uses block k + 1 from here.
    let first_dim = rng.dimension();
    let mut state = PathState::new(ray, beta, first_dim + 2 * LAYOUT.per_bounce);
    let reference = if mode == TransportMode::Importance { light_roulette_reference(beta) } else { 1.0 };
    let roulette = Roulette::Throughput { reference };
    loop {
        if path.len() >= max_vertices {
            if params.max_depth.0 < 0 {
                counters.truncated += 1;
            }
            return;
        }
        let n = path.len();
        let Some(prev) = path.last().copied() else { return };
        let Some(hit) = walk.trace(tracer, &state, counters) else {
            // Camera paths that escape end on the infinite lights.
            if mode == TransportMode::Radiance && scene.infinite_lights().next().is_some() {
                let mut v = Vertex::infinite(prev.exit.p + state.ray.dir, state.beta, VertexPdf::ZERO);
                set_densities(scene, path, &prev, &mut v, mode);
                let _ = path.push(v);
            }
            return;
        };
        // Attenuate by an absorbing medium the segment crossed.
        Walk::pass_medium(scene, &mut state, &hit);
        // The junction: which point keeps the BSDF and which starts the next segment.
        let moved = walk.junction(tracer, &mut state, &hit, junctions.as_deref_mut(), counters);
        let (shading, exit, kernel_ratio) = match (moved, mode) {
            (None, _) => (hit, hit, 1.0),
            (Some(m), TransportMode::Radiance) => (hit, m.at, m.ratio),
            (Some(m), TransportMode::Importance) => (m.at, hit, m.ratio),
        };
        let sp = SurfacePoint::new(shading, -state.ray.dir);
        let mut v = Vertex {
            kind: VertexKind::Surface,
            p: shading.p,
            ng: shading.ng,
            frame: sp.frame,
            wo: sp.wo,
            material: shading.material,
            uv: shading.uv,
            emitter: shading.emitter,
            beta: state.beta,
            delta: false,
            pdf_fwd: VertexPdf::ZERO,
            pdf_rev: VertexPdf::ZERO,
            exit: Exit::at(exit.p, exit.ng, exit.ns, exit.material),
            kernel_ratio,
        };
        set_densities(scene, path, &prev, &mut v, mode);
        if path.push(v).is_err() || path.len() >= max_vertices {
            return;
        }

        // Sample the BSDF for the next direction. The next segment leaves from: the exit
        // toward the light side (radiance), the shading point toward the camera side
        // (importance). Its cosine is taken there (eq. 6).
        let material = scene.material(shading.material, shading.uv);
        let moved_start = (mode == TransportMode::Radiance && moved.is_some()).then_some(&exit);
        match walk.scatter(params, &mut state, &sp, sp.frame.to_local(sp.wo), &material, moved_start, roulette, rng) {
            Leave::Continues(b) => path[n].delta |= b.delta,
            Leave::Ended(b) => {
                path[n].delta |= b.delta;
                return;
            }
            Leave::Stopped => return,
        }
    }
}

/// The new vertex `v`'s forward density from `prev` (the path's last vertex) and, now
/// that `prev`'s successor is known, the reverse density of reaching the vertex before
/// `prev` from it: both ways through `prev` at once where both exist
/// ([`Vertex::pdf_along_both_ways`]).
#[inline]
fn set_densities(scene: &Scene, path: &mut SubPath, prev: &Vertex, v: &mut Vertex, mode: TransportMode) {
    let n = path.len();
    if n >= 2 {
        let (fwd, rev) = prev.pdf_along_both_ways(scene, &path[n - 2], v, mode);
        v.pdf_fwd = fwd;
        path[n - 2].pdf_rev = rev;
    } else {
        v.pdf_fwd = prev.pdf_along(scene, None, v, mode);
    }
}
