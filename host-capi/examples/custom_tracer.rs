//! Embedding the `no_std` core from Rust with a ray tracer of one's own: the core reads
//! the scene and asks for rays through the `RayQuery` trait; here a brute-force tracer
//! (every triangle for every ray) stands in for an engine's. The core's serial runner
//! renders passes into the core's film. (`cargo run --release -p ember-capi --example
//! custom_tracer`; docs/embedding.md.)

use ember_core::estimators::PhaseBuffers;
use ember_core::estimators::{EstimatorKind, Renderer};
use ember_core::geometry::{Ray, RayQuery, SurfaceHit};
use ember_core::math::Vec2;
use ember_core::render::{Context, Film, render_pass, run_phases};
use ember_core::shapes::SceneGeometry;
use ember_core::transport::{MaxDepth, RenderParams};

/// Every triangle for every ray (Möller–Trumbore).
struct Linear {
    geometry: SceneGeometry,
}

impl Linear {
    fn hit(&self, ray: &Ray, any: bool) -> Option<SurfaceHit> {
        let mut best: Option<SurfaceHit> = None;
        let mut t_max = ray.t_max;
        for tri in &self.geometry.triangles {
            let (e1, e2) = (tri.p[1] - tri.p[0], tri.p[2] - tri.p[0]);
            let h = ray.dir.cross(e2);
            let det = e1.dot(h);
            if det == 0.0 {
                continue;
            }
            let s = ray.origin - tri.p[0];
            let u = s.dot(h) / det;
            let q = s.cross(e1);
            let v = ray.dir.dot(q) / det;
            let t = e2.dot(q) / det;
            if u < 0.0 || v < 0.0 || u + v > 1.0 || !(t > 0.0 && t < t_max) {
                continue;
            }
            t_max = t;
            let ng = e1.cross(e2).normalize();
            best = Some(SurfaceHit { t, p: ray.at(t), ng, ns: ng, uv: Vec2::new(u, v), material: tri.material, emitter: tri.emitter });
            if any {
                break;
            }
        }
        best
    }
}

impl RayQuery for Linear {
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        self.hit(ray, false)
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.hit(ray, true).is_some()
    }
}

fn main() {
    let (scene, geometry, _) = ember_core::scene::builtin::cornell_box(32, 32).build().expect("the built-in box builds");
    let tracer = Linear { geometry };
    let params = RenderParams { max_depth: MaxDepth(6), seed: 1, ..RenderParams::default() };
    let mut renderer = Renderer::new(&scene, params, EstimatorKind::Bdpt.default_config()).expect("valid configuration");
    let ctx = Context { scene: &scene, tracer: &tracer };
    let mut film = Film::new(32, 32);
    let mut buffers = PhaseBuffers::new();
    run_phases(&mut renderer, &ctx, &mut Film::new(0, 0), &mut buffers); // setup (none for BDPT)
    for pass in 0..8 {
        render_pass(&mut renderer, &ctx, &mut film, &mut buffers, pass);
    }
    let mean: f64 = film.to_rgb_f32().iter().map(|p| (p[0] + p[1] + p[2]) as f64 / 3.0).sum::<f64>() / film.pixels() as f64;
    println!("custom tracer: {} passes of BDPT on the built-in box, image mean {mean:.4}", film.passes());
    assert!(mean > 0.0 && mean.is_finite());
}
