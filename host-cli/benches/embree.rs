//! Our BVH4 (`Accel`) against Embree 3.13 (`EmbreeAccel`, feature `embree`) on the rays
//! the path tracer really asks for. Results and their reading: docs/performance.md,
//! "Our BVH4 against Embree 3.13".
//!
//! # Rays
//! For every suite scene (`../shared/scenes/*/scene.xml`, at the file's resolution and
//! `max_depth`) and for a procedural scene of a million triangles (`big_scene`: the
//! built-in Cornell box around a displaced sphere tessellated into 710 × 710 quads), one
//! untimed run of PT (`pt::render_pixels`, `PASSES` passes, one thread, seed 0) through
//! a recording `RayQuery` keeps every ray given to `intersect` (closest: camera rays and
//! bounces) and to `occluded` (shadow rays), in the order PT made them. A second run at
//! `max_depth` 1 records the camera rays alone (pixel order: coherent).
//!
//! # Timing
//! Then exactly those rays are traced, one thread, through: our `Accel`, one ray at a time
//! (`intersect_primitive` / `occluded`); Embree one ray at a time (`rtcIntersect1` /
//! `rtcOccluded1`); Embree on consecutive groups of 4, 8 and 16 recorded rays
//! (`rtcIntersect4/8/16`, `rtcOccluded4/8/16`; the coherent flag on camera rays only, as
//! Mitsuba sets it). Every variant writes the same full answer (the `SurfaceHit` and the
//! primitive, or the occlusion flag) into an output slice. `ROUNDS` rounds, the
//! variants' order rotating each round; medians are printed.
//!
//! # Agreement
//! Ours against Embree one ray at a time and 16 wide: the share of closest-hit rays with
//! the same answer (same primitive, or both missing), those whose t differs by more than
//! 1e-4 relative, those where only one hits; occlusion answers that differ, with the
//! number of those that are grazing (the hit that decides lies within 1e-3 of a
//! triangle edge in barycentrics, or meets its plane at |cos| < 0.01, or lies within
//! 1e-3 of either end of the segment).
//!
//! # Build and memory
//! Each structure built `BUILDS` times over the scene's geometry (best time kept): ours,
//! Embree with one build thread and with its default (every hardware thread). Bytes per
//! triangle: each structure's heap (`AccelBytes`: ours by `Vec` capacities, Embree's by
//! its memory monitor plus the shared vertex and index arrays), and Embree's peak while
//! building.
//!
//! Run: `scripts/bench-embree.sh` (or `cargo bench -p ember-cli --features embree --bench
//! embree`); `EMBREE_NOT_ROBUST=1` builds Embree without `RTC_SCENE_FLAG_ROBUST`;
//! `EMBER_BENCH_SCENES=a,b` limits the scenes (`big` names the procedural one).

use std::cell::RefCell;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

use ember_cli::estimators::CoreRenderer;
use ember_core::Rgb;
use ember_core::bsdf::Material;
use ember_core::estimators::{EstimatorKind, pt};
use ember_core::geometry::{Ray, RayQuery, SurfaceHit};
use ember_core::math::Vec3;
use ember_core::scene::SceneGeometry;
use ember_core::scene::builtin;
use ember_formats::mitsuba;
use ember_host::accel::embree::{BuildOptions, EmbreeAccel, Lanes};
use ember_host::accel::{Accel, PrimitiveRef};
use ember_host::scene::PreparedScene;

const PASSES: u32 = 2;
const ROUNDS: usize = 5;
const BUILDS: usize = 3;
/// Quads per side of the big scene's sphere: 2 · 710² ≈ 1.008 M triangles.
const BIG_QUADS: usize = 710;
const BIG_RES: u32 = 256;

/// Forwards to the `Accel` and keeps every query ray.
struct Recorder<'a> {
    accel: &'a Accel,
    closest: RefCell<Vec<Ray>>,
    shadow: RefCell<Vec<Ray>>,
}

impl RayQuery for Recorder<'_> {
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        self.closest.borrow_mut().push(*ray);
        self.accel.intersect(ray)
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.shadow.borrow_mut().push(*ray);
        self.accel.occluded(ray)
    }
}

/// A scene ready for the comparison: the renderer (with our `Accel`) and its geometry.
struct Loaded {
    name: String,
    renderer: CoreRenderer,
    camera_only: CoreRenderer,
    geometry: SceneGeometry,
}

fn load_file(path: &Path) -> Loaded {
    let prepare = || {
        let loaded = mitsuba::load_scene(path, &mitsuba::LoadOptions { defaults: Vec::new(), width: None, height: None }).expect("suite scene loads");
        let (scene, geometry, warnings) = loaded.builder.build().expect("suite scene builds");
        let prepared = PreparedScene::new(path.display().to_string(), scene, &geometry, warnings, loaded.max_depth, loaded.spp, Vec::new());
        (prepared, geometry)
    };
    let (prepared, geometry) = prepare();
    let depth = prepared.max_depth.unwrap_or(-1);
    let renderer = CoreRenderer::new(prepared, EstimatorKind::Pt, depth, 0).expect("PT renderer");
    let camera_only = CoreRenderer::new(prepare().0, EstimatorKind::Pt, 1, 0).expect("PT renderer");
    let name = path.parent().and_then(Path::file_name).map_or("?".into(), |n| n.to_string_lossy().into_owned());
    Loaded { name, renderer, camera_only, geometry }
}

/// The built-in Cornell box around a sphere of radius about 0.55, radially displaced by
/// a few sines, tessellated into `BIG_QUADS`² quads (no vertex normals). Deterministic.
fn big_scene() -> Loaded {
    let build = || {
        let mut b = builtin::cornell_box(BIG_RES, BIG_RES);
        let grey = b.add_material(Material::diffuse(Rgb::new(0.5, 0.5, 0.5)));
        let n = BIG_QUADS;
        let mut positions = Vec::with_capacity((n + 1) * (n + 1));
        for i in 0..=n {
            for j in 0..=n {
                let theta = std::f32::consts::PI * i as f32 / n as f32;
                let phi = std::f32::consts::TAU * j as f32 / n as f32;
                let r = 0.55 + 0.06 * (8.0 * theta).sin() * (6.0 * phi).cos() + 0.015 * (23.0 * theta + phi).sin();
                positions.push(Vec3::new(0.0, 0.9, 0.0) + Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()) * r);
            }
        }
        let at = |i: usize, j: usize| (i * (n + 1) + j) as u32;
        let mut indices = Vec::with_capacity(2 * n * n);
        for i in 0..n {
            for j in 0..n {
                indices.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                indices.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        b.add_mesh(&positions, None, &indices, grey, None);
        let (scene, geometry, warnings) = b.build().expect("big scene builds");
        (PreparedScene::new("big".into(), scene, &geometry, warnings, None, None, Vec::new()), geometry)
    };
    let (prepared, geometry) = build();
    let renderer = CoreRenderer::new(prepared, EstimatorKind::Pt, -1, 0).expect("PT renderer");
    let camera_only = CoreRenderer::new(build().0, EstimatorKind::Pt, 1, 0).expect("PT renderer");
    Loaded { name: format!("big ({}k tris)", geometry.triangles.len() / 1000), renderer, camera_only, geometry }
}

/// PT's rays over `PASSES` passes of the whole image, one thread: (closest, shadow).
fn record(r: &CoreRenderer) -> (Vec<Ray>, Vec<Ray>) {
    let accel = &r.prepared.accel;
    let cam = &r.prepared.scene.camera;
    let pixels = cam.width() * cam.height();
    let mut out = vec![Rgb::ZERO; pixels as usize];
    let rec = Recorder { accel, closest: RefCell::new(Vec::new()), shadow: RefCell::new(Vec::new()) };
    for pass in 0..PASSES {
        pt::render_pixels(&r.prepared.scene, &rec, r.renderer.params(), pass, 0..pixels, &mut out);
    }
    (rec.closest.into_inner(), rec.shadow.into_inner())
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
}

/// Who traces: ours, or Embree at a width.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Variant {
    Ours,
    Embree(Lanes),
}

const VARIANTS: [Variant; 5] =
    [Variant::Ours, Variant::Embree(Lanes::One), Variant::Embree(Lanes::Four), Variant::Embree(Lanes::Eight), Variant::Embree(Lanes::Sixteen)];

fn label(v: Variant) -> &'static str {
    match v {
        Variant::Ours => "ours",
        Variant::Embree(Lanes::One) => "E-1",
        Variant::Embree(Lanes::Four) => "E-4",
        Variant::Embree(Lanes::Eight) => "E-8",
        Variant::Embree(Lanes::Sixteen) => "E-16",
    }
}

type Answer = Option<(SurfaceHit, PrimitiveRef)>;

fn closest(v: Variant, ours: &Accel, theirs: &EmbreeAccel, rays: &[Ray], coherent: bool, out: &mut [Answer]) -> f64 {
    let t = Instant::now();
    match v {
        Variant::Ours => rays.iter().zip(out.iter_mut()).for_each(|(r, o)| *o = ours.intersect_primitive(black_box(r))),
        Variant::Embree(lanes) => theirs.intersect_packets_of(black_box(rays), lanes, coherent, out),
    }
    black_box(&*out);
    rays.len() as f64 / t.elapsed().as_secs_f64() / 1e6
}

fn occlusion(v: Variant, ours: &Accel, theirs: &EmbreeAccel, rays: &[Ray], out: &mut [bool]) -> f64 {
    let t = Instant::now();
    match v {
        Variant::Ours => rays.iter().zip(out.iter_mut()).for_each(|(r, o)| *o = ours.occluded(black_box(r))),
        Variant::Embree(lanes) => theirs.occluded_packets_of(black_box(rays), lanes, false, out),
    }
    black_box(&*out);
    rays.len() as f64 / t.elapsed().as_secs_f64() / 1e6
}

/// Closest-hit agreement: (same answer, t off by > 1e-4 relative, the largest t among
/// those, only one hits).
fn agree_closest(a: &[Answer], b: &[Answer]) -> (usize, usize, f32, usize) {
    let (mut same, mut far, mut far_t, mut one) = (0, 0, 0.0f32, 0);
    for (x, y) in a.iter().zip(b) {
        match (x, y) {
            (None, None) => same += 1,
            (Some((hx, px)), Some((hy, py))) => {
                same += (px == py) as usize;
                if (hx.t - hy.t).abs() > 1e-4 * hx.t.abs().max(hy.t.abs()) {
                    far += 1;
                    far_t = far_t.max(hx.t);
                }
            }
            _ => one += 1,
        }
    }
    (same, far, far_t, one)
}

/// Whether the hit deciding a disagreement is grazing (see the module documentation).
fn grazing(g: &SceneGeometry, ray: &Ray, hit: &Answer) -> bool {
    let Some((h, prim)) = hit else { return true };
    let near_end = h.t < 1e-3 * ray.t_max.min(1e30) || (ray.t_max.is_finite() && h.t > (1.0 - 1e-3) * ray.t_max);
    let cos = ray.dir.normalize().dot(h.ng).abs();
    let edge = match prim {
        PrimitiveRef::Triangle(i) => {
            let p = g.triangles[*i as usize].p.map(|v| v.as_dvec3());
            let q = h.p.as_dvec3();
            let area = |a: glam::DVec3, b: glam::DVec3, c: glam::DVec3| (b - a).cross(c - a).length();
            let whole = area(p[0], p[1], p[2]);
            [area(q, p[1], p[2]), area(p[0], q, p[2]), area(p[0], p[1], q)].iter().any(|&b| b / whole < 1e-3)
        }
        PrimitiveRef::Sphere(_) => false,
    };
    near_end || cos < 0.01 || edge
}

struct SceneResult {
    name: String,
    triangles: usize,
    /// Mrays/s per variant: closest, occlusion, camera.
    rates: Vec<(Variant, f64, f64, f64)>,
    counts: (usize, usize, usize),
}

fn run_scene(s: &Loaded, options: BuildOptions) -> SceneResult {
    let (closest_rays, shadow_rays) = record(&s.renderer);
    let (camera_rays, _) = record(&s.camera_only);
    let ours = &s.renderer.prepared.accel;

    // Build times and bytes.
    let best = |f: &dyn Fn() -> f64| (0..BUILDS).map(|_| f()).fold(f64::INFINITY, f64::min);
    let timed = |f: &dyn Fn()| {
        let t = Instant::now();
        f();
        t.elapsed().as_secs_f64()
    };
    let t_ours = best(&|| timed(&|| drop(black_box(Accel::new(&s.geometry)))));
    let t_e1 = best(&|| timed(&|| drop(black_box(EmbreeAccel::with_options(&s.geometry, BuildOptions { threads: 1, ..options }).expect("Embree builds")))));
    let t_eall = best(&|| timed(&|| drop(black_box(EmbreeAccel::with_options(&s.geometry, options).expect("Embree builds")))));
    let theirs = EmbreeAccel::with_options(&s.geometry, options).expect("Embree builds");
    let tris = ours.triangle_count();
    assert_eq!(tris, theirs.triangle_count(), "both keep the same triangles");
    let (ob, (eb, peak)) = (ours.bytes(), theirs.bytes());
    let per = |b: u64| b as f64 / tris.max(1) as f64;
    println!("## {} — {} triangles, {} spheres", s.name, tris, ours.sphere_count());
    println!(
        "rays: {} closest, {} shadow, {} camera ({} passes); build: ours {:.2} ms, Embree {:.2} ms (1 thread) / {:.2} ms (default threads)",
        closest_rays.len(),
        shadow_rays.len(),
        camera_rays.len(),
        PASSES,
        1e3 * t_ours,
        1e3 * t_e1,
        1e3 * t_eall
    );
    println!(
        "bytes/triangle: ours {:.0} (hierarchy {:.0}, vertices {:.0}, attributes {:.0}); Embree {:.0} (its own {:.0}, shared vertex+index {:.0}, attributes {:.0}; build peak {:.0})",
        per(ob.total() - ob.spheres),
        per(ob.hierarchy),
        per(ob.vertices),
        per(ob.attributes),
        per(eb.total() - eb.spheres),
        per(eb.hierarchy),
        per(eb.vertices),
        per(eb.attributes),
        per(peak)
    );

    // Interleaved rounds.
    let mut c_out: Vec<Vec<Answer>> = VARIANTS.iter().map(|_| vec![None; closest_rays.len()]).collect();
    let mut s_out: Vec<Vec<bool>> = VARIANTS.iter().map(|_| vec![false; shadow_rays.len()]).collect();
    let mut cam_out = vec![None; camera_rays.len()];
    let mut rates: Vec<[Vec<f64>; 3]> = VARIANTS.iter().map(|_| [vec![], vec![], vec![]]).collect();
    for round in 0..ROUNDS {
        for k in 0..VARIANTS.len() {
            let i = (k + round) % VARIANTS.len();
            let v = VARIANTS[i];
            rates[i][0].push(closest(v, ours, &theirs, &closest_rays, false, &mut c_out[i]));
            rates[i][1].push(occlusion(v, ours, &theirs, &shadow_rays, &mut s_out[i]));
            rates[i][2].push(closest(v, ours, &theirs, &camera_rays, v != Variant::Ours, &mut cam_out));
        }
    }
    let rates: Vec<_> = VARIANTS.iter().zip(rates).map(|(&v, [c, o, cam])| (v, median(c), median(o), median(cam))).collect();
    println!("| Mrays/s | {} |", VARIANTS.map(label).join(" | "));
    for (k, name) in ["closest (PT)", "occlusion (PT)", "camera closest"].iter().enumerate() {
        let row: Vec<String> = rates.iter().map(|r| format!("{:.2}", [r.1, r.2, r.3][k])).collect();
        println!("| {name} | {} |", row.join(" | "));
    }

    // Agreement with ours.
    for (i, who) in [(1, "E-1"), (4, "E-16")] {
        let (same, far, far_t, one) = agree_closest(&c_out[0], &c_out[i]);
        let differ: Vec<usize> = (0..shadow_rays.len()).filter(|&k| s_out[0][k] != s_out[i][k]).collect();
        let graze = differ
            .iter()
            .filter(|&&k| {
                let r = &shadow_rays[k];
                let hit = if s_out[0][k] { ours.intersect_primitive(r) } else { theirs.intersect_primitive(r) };
                grazing(&s.geometry, r, &hit)
            })
            .count();
        println!(
            "agreement ours / {who}: closest same {:.4} % ({} t off > 1e-4 rel., all at t <= {:.1e}; {} hit/miss); occlusion differs on {} of {} ({} grazing)",
            100.0 * same as f64 / closest_rays.len().max(1) as f64,
            far,
            far_t,
            one,
            differ.len(),
            shadow_rays.len(),
            graze
        );
    }
    println!();
    SceneResult { name: s.name.clone(), triangles: tris, rates, counts: (closest_rays.len(), shadow_rays.len(), camera_rays.len()) }
}

fn suite_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes")
}

/// Embree answering one ray per call: the lane loop at width 1.
struct OneAtATime<'a>(&'a EmbreeAccel);

impl RayQuery for OneAtATime<'_> {
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        self.0.intersect(ray)
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.0.occluded(ray)
    }
}

/// PT itself (`pt::render_pixels`, `PASSES` passes of the whole image, one thread) through
/// ours (width 1), Embree one ray per call (width 1) and Embree 16 rays per call (the
/// lane loop at width 16), `ROUNDS` interleaved rounds: ksamples/s, medians. The two
/// Embree images must be equal bit for bit (the lane loop's width does not change them).
fn pt_on_lanes(s: &Loaded, options: BuildOptions) {
    let r = &s.renderer;
    let embree = EmbreeAccel::with_options(&s.geometry, options).expect("Embree builds");
    let cam = &r.prepared.scene.camera;
    let pixels = cam.width() * cam.height();
    let render = |tracer: &dyn RayQuery| {
        let mut out = vec![Rgb::ZERO; pixels as usize];
        let mut images = Vec::new();
        let start = Instant::now();
        for pass in 0..PASSES {
            pt::render_pixels(&r.prepared.scene, tracer, r.renderer.params(), pass, 0..pixels, &mut out);
            images.push(out.clone());
        }
        ((PASSES * pixels) as f64 / start.elapsed().as_secs_f64() / 1e3, images)
    };
    let (mut ours, mut e1, mut e16) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..ROUNDS {
        ours.push(render(&r.prepared.accel).0);
        let (a, image1) = render(&OneAtATime(&embree));
        let (b, image16) = render(&embree);
        assert!(image1 == image16, "{}: Embree's image at width 16 differs from width 1", s.name);
        e1.push(a);
        e16.push(b);
    }
    let (o, a, b) = (median(ours), median(e1), median(e16));
    println!("| {} | {o:.0} | {a:.0} | {b:.0} | {:.2} | {:.2} |", s.name, a / o, b / o);
}

fn main() {
    let robust = std::env::var("EMBREE_NOT_ROBUST").map_or(true, |v| v != "1");
    let options = BuildOptions { robust, threads: 0 };
    let wanted: Option<Vec<String>> = std::env::var("EMBER_BENCH_SCENES").ok().map(|v| v.split(',').map(str::to_owned).collect());
    let wants = |n: &str| wanted.as_ref().is_none_or(|w| w.iter().any(|x| x == n));
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(suite_dir()).expect("../shared/scenes").filter_map(|e| e.ok().map(|e| e.path())).collect();
    dirs.sort();
    if std::env::var("EMBER_BENCH_PT").is_ok_and(|v| v == "1") {
        println!("# PT on the lane loop, ksamples/s, one thread, {ROUNDS} interleaved rounds, medians\n");
        println!("| scene | ours (width 1) | Embree, width 1 | Embree, width 16 | E-1 / ours | E-16 / ours |");
        println!("|---|---|---|---|---|---|");
        for dir in dirs.iter().filter(|d| d.join("scene.xml").exists()) {
            let name = dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
            if wants(&name) {
                pt_on_lanes(&load_file(&dir.join("scene.xml")), options);
            }
        }
        return;
    }
    let mut results = Vec::new();
    println!("# Ours (BVH4) against Embree (robust: {robust}), one thread, {ROUNDS} interleaved rounds, medians\n");
    if let Some(info) = EmbreeAccel::new(&probe_scene()).ok().and_then(|e| e.device_info()) {
        println!("Embree device: version {}, native 4/8/16-wide packets {:?}, tasking {}\n", info.version, info.native, info.tasking);
    }
    for dir in dirs.iter().filter(|d| d.join("scene.xml").exists()) {
        let name = dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if wants(&name) {
            results.push(run_scene(&load_file(&dir.join("scene.xml")), options));
        }
    }
    if wants("big") {
        results.push(run_scene(&big_scene(), options));
    }

    // The summary: ours against Embree one ray and 16 wide.
    println!("\n| scene | tris | closest ours | E-1 | E-16 | E-1/ours | occlusion ours | E-1 | E-16 | E-1/ours | camera ours | E-16 coherent | E-16/ours |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for r in &results {
        let rate = |v: Variant| *r.rates.iter().find(|x| x.0 == v).expect("every variant ran");
        let (o, e1, e16) = (rate(Variant::Ours), rate(Variant::Embree(Lanes::One)), rate(Variant::Embree(Lanes::Sixteen)));
        println!(
            "| {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} |",
            r.name,
            r.triangles,
            o.1,
            e1.1,
            e16.1,
            e1.1 / o.1,
            o.2,
            e1.2,
            e16.2,
            e1.2 / o.2,
            o.3,
            e16.3,
            e16.3 / o.3
        );
        black_box(r.counts);
    }
}

/// A one-triangle scene, only to ask the device what it supports.
fn probe_scene() -> SceneGeometry {
    let mut g = SceneGeometry::default();
    g.triangles.push(ember_core::shapes::Triangle { p: [Vec3::ZERO, Vec3::X, Vec3::Y], n: None, uv: None, material: 0, emitter: None });
    g
}
