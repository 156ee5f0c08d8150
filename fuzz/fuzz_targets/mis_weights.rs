//! Weight code (issue 8): every weight is finite, in [0, 1], and the weights of one
//! sample over all strategies sum to 1.
//!
//! - **BDPT** (first byte even): the Cornell box plus one sphere whose position, radius
//!   and material (any model, roughness 1e-5 … 1, any index) come from the input; camera
//!   and light sub-paths from input-chosen seeds and depths. Every connection's weight is
//!   finite and in [0, 1]; for every full path joined at two non-Dirac vertices, the
//!   sub-paths every other strategy would have produced are rebuilt (as
//!   `tests/tests/bdpt_mis.rs` does) and the recursive weights of all strategies able to
//!   produce the path sum to 1 within 1e-3.
//!   Then path and photon filtering's denominators on the same scene (issue 16): camera
//!   and light nodes of 16 paths each, a kernel radius from the input (1e-4 … 1): every
//!   denominator of a segment that exists is finite and positive (its own node's
//!   technique is among those summed), and the propagated radiance and flux are finite.
//!   Seen failing (seed `filter-denominator-roughness`): a rough dielectric at roughness
//!   1e-5 whose pdf re-evaluated to 0 for the direction its sampler drew, before the own
//!   technique used the sampler's density.
//!   Then, on one input in four, bidirectional path filtering's (issue 17) over the camera nodes and the light
//!   nodes with their emission nodes together, every reuse mode: every denominator of a
//!   segment that exists is finite and positive, every row coefficient finite and
//!   non-negative (the pair correction's D_a − D_a,u and D_b − D_b,emit / N_L stay
//!   positive), and the propagated radiance finite.
//! - **MMIS** (first byte odd): 1–4 techniques, 1–4 pairs each, with conditional
//!   densities from the input's raw f64 bits (NaN, ∞, negative, 1e±300 included) at 1–4
//!   evaluation points: `Mmis::balance_weight` over all techniques sums to 1 where the
//!   denominator is positive (and every weight is 0 where it is not); the tuple weights
//!   of `product_of_sums` over every choice of conditioning sample sum to 1 likewise.
#![no_main]

use std::sync::atomic::{AtomicU64, Ordering};

use ember_core::bsdf::{Material, MicrofacetKind};
use ember_core::path::mis::mis_weight;
use ember_core::path::{LightPointSample, Vertex, VertexKind, camera_subpath, connect, light_subpath};
use ember_core::scene::Context;
use ember_core::transport::{Counters, MaxDepth, RenderParams};
use ember_core::mmis::{Mmis, Pair, Technique, product_of_sums, tuple_weight};
use ember_core::rng::{SampleStream, Stream};
use ember_core::scene::Scene;
use ember_core::segment::Kernel;
use ember_core::estimators::filter::nodes::{NONE, NodeKind};
use ember_core::estimators::filter::bridge::bridge_end;
use ember_core::estimators::filter::{Bidirectional, FilterGraph, Neighbourhood, NodeGrid, kernel_points, trace_bridges, trace_camera_nodes, trace_light_nodes};
use ember_core::spectrum::Rgb;
use ember_fuzz::Bytes;
use ember_tests::bdpt_oracle::for_each_strategy_split;
use ember_tests::scenes::cornell;
use ember_tests::tracer::BruteForce;
use glam::{Vec2, Vec3};
use libfuzzer_sys::fuzz_target;

fn check_weight(w: f64, what: &str) {
    assert!(w.is_finite() && (0.0..=1.0 + 1e-6).contains(&w), "{what}: weight {w}");
}

// ---------------------------------------------------------------- BDPT

/// Film resolution of the fuzzed Cornell box.
const RES: u32 = 8;

fn sphere_material(b: &mut Bytes) -> Material {
    let distr = if b.u8() & 1 == 0 { MicrofacetKind::Beckmann } else { MicrofacetKind::Ggx };
    let alpha = b.log_uniform(1e-5, 1.0);
    let ior = 1.0 + 2.0 * b.unit();
    let c = Rgb::new(b.unit(), b.unit(), b.unit());
    match b.u8() % 5 {
        0 => Material::diffuse(c),
        1 => Material::conductor(Rgb::splat(0.2), Rgb::splat(3.0), c),
        2 => Material::rough_conductor(distr, alpha, Rgb::splat(0.2), Rgb::splat(3.0), c),
        3 => Material::dielectric(ior, 1.0, c, c),
        _ => Material::rough_dielectric(distr, alpha, ior, 1.0, c, c),
    }
}

static FULL_PATHS: AtomicU64 = AtomicU64::new(0);
static BDPT_INPUTS: AtomicU64 = AtomicU64::new(0);

fn bdpt(b: &mut Bytes, hash: u64) {

    let mut builder = cornell(RES, RES);
    let m = builder.add_material(sphere_material(b));
    let centre = Vec3::new(1.4 * b.unit() - 0.7, 0.2 + 1.6 * b.unit(), 1.4 * b.unit() - 0.7);
    builder.add_sphere(centre, b.log_uniform(0.02, 0.3), false, m, None);
    let (scene, geometry, _) = builder.build().expect("the Cornell box with a sphere builds");
    let tracer = BruteForce::new(geometry);
    // At least 3 segments, so that full paths with s, t ≥ 2 exist.
    let depth = 3 + (b.u8() % 6) as i32;
    // Paths from a hash of the whole input: libFuzzer starts with short inputs, which
    // read as zeros past their end, and byte-derived seeds then repeat one path.
    let seed = hash;
    let params = RenderParams { max_depth: MaxDepth(depth), seed, ..RenderParams::default() };
    for pair in 0..4u32 {
        paths_of_one_sample(b, &scene, &tracer, &params, (seed >> 32) as u32 ^ pair, depth);
    }
    filtering(b, &scene, &tracer, &params, depth as u32);
    // The target must actually exercise full paths, not only reject them (about 6 % of
    // path pairs yield one, measured; the floor is 1/32 of inputs).
    let inputs = BDPT_INPUTS.fetch_add(1, Ordering::Relaxed) + 1;
    if inputs % 2048 == 0 {
        let paths = FULL_PATHS.load(Ordering::Relaxed);
        assert!(paths >= inputs / 32, "only {paths} full paths checked in {inputs} BDPT inputs");
    }
}

fn paths_of_one_sample(b: &mut Bytes, scene: &Scene, tracer: &BruteForce, params: &RenderParams, index: u32, depth: i32) {
    let mut counters = Counters::default();
    let mut rng = SampleStream::for_sample(params.seed, Stream::Camera, index, 0, 0);
    let film = rng.next_2d() * Vec2::splat(RES as f32);
    let n_max = depth as usize + 1;
    let cam = camera_subpath(scene, tracer, params, film, n_max, &mut rng, &mut counters);
    let mut lrng = SampleStream::for_sample(params.seed, Stream::Light, index, 0, 0);
    let light = light_subpath(scene, tracer, params, n_max - 1, &mut lrng, &mut counters);
    for t in 1..=cam.len() {
        for s in 0..=light.len() {
            if (s == 1 && t == 1) || s + t < 2 || s + t > n_max {
                continue;
            }
            let u = LightPointSample { u_light: b.unit(), u_point: b.unit2() };
            let Some(c) = connect(&Context { scene, tracer }, &light, &cam, s, t, u, &mut counters) else { continue };
            let c = c.weighted(mis_weight(scene, &light, &cam, c.sampled.as_ref(), s, t));
            check_weight(c.weight as f64, &format!("BDPT connection (s, t) = ({s}, {t})"));
            assert!(c.value.is_finite(), "BDPT ({s}, {t}) value {:?}", c.value);
            if s < 2 || t < 2 || cam[t - 1].kind == VertexKind::InfiniteLight {
                continue;
            }
            let mut x: Vec<Vertex> = light[..s].to_vec();
            x.extend(cam[..t].iter().rev().copied());
            let n = x.len();
            let mut sum = 0.0f64;
            for_each_strategy_split(scene, &x, |s2, t2, l, c| {
                let w = mis_weight(scene, l, c, None, s2, t2) as f64;
                check_weight(w, &format!("BDPT split ({s2}, {t2}) of a {n}-vertex path"));
                sum += w;
            });
            assert!((sum - 1.0).abs() <= 1e-3, "BDPT weights of a {n}-vertex path (joined at ({s}, {t})) sum to {sum}");
            FULL_PATHS.fetch_add(1, Ordering::Relaxed);
        }
    }
}

// ---------------------------------------------------------------- filtering

fn filtering(b: &mut Bytes, scene: &Scene, tracer: &BruteForce, params: &RenderParams, segments: u32) {
    let radius = b.log_uniform(1e-4, 1.0);
    let (mut cam, mut first, mut sky) = (Vec::new(), Vec::new(), Vec::new());
    trace_camera_nodes(scene, tracer, params, segments, 0, 0..16, &mut cam, &mut first, &mut sky);
    let (mut light, mut pred, mut base) = (Vec::new(), Vec::new(), Vec::new());
    trace_light_nodes(scene, tracer, params, segments, 16, 0, 0..16, false, false, &mut light, &mut pred, &mut base);
    for (nodes, is_light) in [(&cam, false), (&light, true)] {
        let mut grid = NodeGrid::default();
        grid.build(&nodes, radius * std::f32::consts::SQRT_2);
        let points = kernel_points(nodes);
        let hood = Neighbourhood { scene, nodes, points: &points, grid: &grid, kernel: Kernel::Disk { radius } };
        let dens: Vec<_> = (0..nodes.len() as u32).map(|i| hood.denominators(i)).collect();
        for (u, d) in nodes.iter().zip(&dens) {
            if u.delta {
                continue;
            }
            if u.next.dir != Vec3::ZERO && !u.next.delta {
                assert!(d.next.is_finite() && d.next > 0.0, "continuation denominator {} (r = {radius})", d.next);
            }
            if u.light.dir != Vec3::ZERO {
                assert!(d.light.is_finite() && d.light > 0.0, "light-segment denominator {} (r = {radius})", d.light);
            }
        }
        let mut graph = FilterGraph::<f32>::new();
        let mut pairs = Vec::new();
        for (i, v) in nodes.iter().enumerate() {
            let (e, d) = if is_light { hood.light_row::<f32>(pred[i], base[i], &dens, &mut pairs) } else { hood.row::<f32>(v, &dens, &mut pairs) };
            graph.push_row(e, d, pairs.iter().copied());
        }
        for l in graph.propagate(segments) {
            assert!(l.iter().all(|c| c.is_finite() && *c >= 0.0), "propagated value {l:?} (r = {radius})");
        }
    }
    // One input in four: its weights cost about six times the rest of the target.
    if b.u8() % 4 == 0 {
        bidirectional(b, scene, tracer, params, segments, radius);
    }
}

/// Bidirectional filtering's weights over 16 camera and 16 light paths (with emission
/// nodes) at kernel radius `radius`.
fn bidirectional(b: &mut Bytes, scene: &Scene, tracer: &BruteForce, params: &RenderParams, segments: u32, radius: f32) {
    let (mut nodes, mut first, mut sky) = (Vec::new(), Vec::new(), Vec::new());
    trace_camera_nodes(scene, tracer, params, segments, 0, 0..16, &mut nodes, &mut first, &mut sky);
    let (mut light, mut pred, mut base) = (Vec::new(), Vec::new(), Vec::new());
    trace_light_nodes(scene, tracer, params, segments, 16, 0, 0..16, true, false, &mut light, &mut pred, &mut base);
    let offset = nodes.len() as u32;
    let shift = |i: u32| if i == NONE { NONE } else { i + offset };
    nodes.extend(light.into_iter().map(|mut n| {
        n.pred = shift(n.pred);
        n.next.node = shift(n.next.node);
        n
    }));
    // Every segment, merges only, or every segment and bridges.
    let mode = b.u8() % 3;
    let mut bridge_choice = None;
    if mode == 2 {
        let ends: Vec<u32> = (0..nodes.len() as u32).filter(|&i| bridge_end(&nodes[i as usize])).collect();
        let mut bridges = Vec::new();
        trace_bridges(scene, tracer, params.seed, 0, &nodes, &ends, 0..nodes.len(), &mut bridges);
        nodes.extend(bridges);
        bridge_choice = (!ends.is_empty()).then(|| 1.0 / ends.len() as f64);
    }
    let mut grid = NodeGrid::default();
    grid.build(&nodes, radius * std::f32::consts::SQRT_2);
    let points = kernel_points(&nodes);
    let hood = Neighbourhood { scene, nodes: &nodes, points: &points, grid: &grid, kernel: Kernel::Disk { radius } };
    let w = Bidirectional { hood, light_paths: 16.0, merges_only: mode == 1, bridge_choice };
    let dens: Vec<_> = (0..nodes.len() as u32).map(|i| w.denominators(i)).collect();
    let ok = |x: f64| x.is_finite() && x > 0.0;
    for (u, d) in nodes.iter().zip(&dens) {
        match u.kind {
            NodeKind::Camera if !u.delta => {
                if u.next.dir != Vec3::ZERO && !u.next.delta {
                    assert!(ok(d.next) && d.next_light >= 0.0, "BPF continuation denominator {d:?} (r = {radius})");
                }
                if u.light.dir != Vec3::ZERO {
                    assert!(ok(d.light), "BPF light-segment denominator {d:?} (r = {radius})");
                }
            }
            NodeKind::Light => assert!(ok(d.arrive) && d.arrive_light >= 0.0, "BPF arriving-segment denominator {d:?} (r = {radius})"),
            _ => {}
        }
    }
    let mut graph = FilterGraph::<f32>::new();
    let mut pairs = Vec::new();
    for v in 0..nodes.len() as u32 {
        let (e, d) = w.row::<f32>(v, &dens, &mut pairs);
        assert!(e.iter().chain(&d).all(|c| c.is_finite() && *c >= 0.0), "BPF row constants {e:?} {d:?} (r = {radius})");
        for (_, c) in &pairs {
            assert!(c.iter().all(|x| x.is_finite() && *x >= 0.0), "BPF coefficient {c:?} (r = {radius})");
        }
        graph.push_row(e, d, pairs.iter().copied());
    }
    for l in graph.propagate(segments) {
        assert!(l.iter().all(|c| c.is_finite()), "BPF propagated value {l:?} (r = {radius})");
    }
}

// ---------------------------------------------------------------- MMIS

/// A technique whose conditional density is a table indexed by (point, pair): the
/// densities are arbitrary f64 bit patterns.
struct Table {
    pdf: Vec<f64>,
    classical: bool,
}

const POINTS: usize = 4;

impl Technique<usize, usize> for Table {
    fn pdf(&self, x: &usize, t: &usize) -> f64 {
        let t = if self.classical { 0 } else { *t };
        self.pdf[t * POINTS + x]
    }
    fn is_classical(&self) -> bool {
        self.classical
    }
}

fn density(b: &mut Bytes) -> f64 {
    match b.u8() % 4 {
        0 => f64::from_bits(u64::from(b.u32()) << 32 | u64::from(b.u32())),
        1 => 10f64.powf(600.0 * b.unit() as f64 - 300.0),
        2 => 0.0,
        _ => b.unit() as f64,
    }
}

fn mmis(b: &mut Bytes) {
    let techniques_n = 1 + (b.u8() % 4) as usize;
    let mut techniques = Vec::new();
    let mut counts = Vec::new();
    let mut pairs = Vec::new();
    for _ in 0..techniques_n {
        let n = 1 + (b.u8() % 4) as usize;
        let classical = b.u8() & 1 == 1;
        let pdf = (0..n * POINTS).map(|_| density(b)).collect();
        techniques.push(Table { pdf, classical });
        counts.push(n);
        pairs.extend((0..n).map(|j| Pair { t: j, x: (b.u8() as usize) % POINTS }));
    }
    let est = Mmis::new(&techniques, &counts, &pairs).expect("counts match the pairs");
    for x in 0..POINTS {
        let weights: Vec<f64> = (0..techniques_n).map(|i| est.balance_weight(i, &x)).collect();
        for &w in &weights {
            check_weight(w, "MMIS balance weight");
        }
        let sum: f64 = weights.iter().sum();
        if est.denominator(&x).is_zero() {
            assert!(sum == 0.0, "MMIS weights {weights:?} where the denominator is zero");
        } else {
            assert!((sum - 1.0).abs() <= 1e-9, "MMIS weights {weights:?} sum to {sum}");
        }
    }

    // Product-of-sums tuple weights: kernel k has `counts[k]` conditional densities.
    let kernels: Vec<Vec<f64>> = techniques.iter().zip(&counts).map(|(t, &n)| (0..n).map(|j| t.pdf[j * POINTS]).collect()).collect();
    let denominator = product_of_sums(kernels.iter().map(|k| k.iter().copied()));
    let mut choice = vec![0usize; kernels.len()];
    let mut sum = 0.0f64;
    loop {
        let w = tuple_weight(choice.iter().zip(&kernels).map(|(&j, k)| k[j]), denominator);
        check_weight(w, "MMIS tuple weight");
        sum += w;
        // Next tuple (odometer order).
        let mut k = 0;
        while k < choice.len() && choice[k] + 1 == kernels[k].len() {
            choice[k] = 0;
            k += 1;
        }
        if k == choice.len() {
            break;
        }
        choice[k] += 1;
    }
    if denominator.is_zero() {
        assert!(sum == 0.0, "tuple weights sum to {sum} with a zero denominator");
    } else {
        assert!((sum - 1.0).abs() <= 1e-9, "tuple weights sum to {sum}, kernels {kernels:?}");
    }
}

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes::new(data);
    // FNV-1a of the whole input.
    let hash = data.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &x| (h ^ x as u64).wrapping_mul(0x0100_0000_01b3));
    if b.u8() & 1 == 0 { bdpt(&mut b, hash) } else { mmis(&mut b) }
});

