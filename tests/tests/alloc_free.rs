//! The per-sample functions allocate nothing: a counting global allocator records every
//! allocation made on this thread while they run.
//!
//! Injected-bug check (done once, reverted): collecting the BDPT strategies into an
//! `alloc::vec::Vec` inside `bdpt::render_pixels` makes this test report allocations.

#![allow(unsafe_code)] // A global allocator is unsafe by definition.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use ember_core::bsdf::{Material, MicrofacetKind, TransportMode};
use ember_core::estimators::{bdpt, lt, pt};
use ember_core::rng::{SampleStream, Stream};
use ember_core::spectrum::Rgb;
use ember_core::transport::{MaxDepth, RenderParams, Splat};
use ember_core::warp;
use ember_tests::scenes::cornell_with_spheres;
use ember_tests::tracer::BruteForce;
use glam::{Vec2, Vec3};

struct Counting;
thread_local! {
    static ACTIVE: Cell<bool> = const { Cell::new(false) };
    /// Per thread, so tests running in parallel do not count each other's allocations.
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if ACTIVE.with(|a| a.get()) {
            ALLOCATIONS.with(|n| n.set(n.get() + 1));
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn count_allocations(f: impl FnOnce()) -> usize {
    let before = ALLOCATIONS.with(Cell::get);
    ACTIVE.with(|a| a.set(true));
    f();
    ACTIVE.with(|a| a.set(false));
    ALLOCATIONS.with(Cell::get) - before
}

#[test]
fn per_sample_functions_do_not_allocate() {
    // Setup allocates, outside the counted region.
    let (scene, geometry, _) = cornell_with_spheres(8, 8).build().unwrap();
    let tracer = BruteForce::new(geometry);
    let params = RenderParams { max_depth: MaxDepth::UNBOUNDED, ..RenderParams::default() };
    let materials = [
        Material::diffuse(Rgb::splat(0.5)),
        Material::rough_conductor(MicrofacetKind::Beckmann, 0.3, Rgb::splat(0.2), Rgb::splat(3.0), Rgb::ONE),
        Material::rough_dielectric(MicrofacetKind::Ggx, 0.3, 1.5, 1.0, Rgb::ONE, Rgb::ONE),
        Material::dielectric(1.5, 1.0, Rgb::ONE, Rgb::ONE),
    ];
    let mut out = vec![Rgb::ZERO; 64];
    let mut sink = 0.0f32;
    let n = count_allocations(|| {
        let mut rng = SampleStream::for_sample(0, Stream::Aux, 0, 0, 0);
        for _ in 0..1000 {
            let u = rng.next_2d();
            sink += warp::sample_cosine_hemisphere(u).z + warp::sample_uniform_cone(u, 0.5).z + warp::invert_concentric_disk(u).x;
            let wo = warp::sample_uniform_sphere(rng.next_2d());
            for m in &materials {
                if let Some(s) = m.sample(wo, rng.next_f32(), rng.next_2d(), TransportMode::Radiance) {
                    sink += m.eval(wo, s.wi, TransportMode::Importance).r + m.pdf(wo, s.wi, TransportMode::Radiance).0;
                }
            }
            for l in &scene.lights {
                if let Some(s) = l.sample_li(Vec3::new(0.1, 1.0, 0.2), rng.next_2d()) {
                    sink += s.pdf.0;
                }
                if let Some(e) = l.sample_le(rng.next_2d(), rng.next_2d()) {
                    sink += e.pdf_dir.0;
                }
            }
            if let Some(c) = scene.camera.sample_wi(Vec3::new(0.0, 1.0, 0.0), Vec2::ZERO) {
                sink += c.importance;
            }
            sink += scene.camera.generate_ray(Vec2::new(3.5, 4.5)).dir.x;
        }
        for pass in 0..4 {
            pt::render_pixels(&scene, &tracer, &params, pass, 0..64, &mut out);
            let mut splat = |s: Splat| sink += s.value.r;
            lt::trace_paths(&scene, &tracer, &params, pass, 0..64, &mut splat);
            bdpt::render_pixels(&scene, &tracer, &params, pass, 0..64, &mut out, &mut splat);
        }
    });
    assert!(sink.is_finite());
    assert_eq!(n, 0, "per-sample code allocated {n} times");
}

/// The render protocol's per-pass phases allocate nothing once the buffers have grown:
/// PT, LT, BDPT and LVCBPT through the core's serial runner, passes 4..12 replayed after
/// passes 0..12 (a pass's random numbers depend on its index alone, so a replayed pass
/// needs no more room than it took the first time). The chunk outputs, the LVCBPT
/// light-path store and cache and the film's staging all keep their capacity from pass
/// to pass. (Fresh passes may still grow a buffer to a new high-water mark: after the
/// one-phase estimators' chunks shrank to 64 items at this size, LT's passes 4..12 grew
/// a chunk's splats twice after 4 warm-up passes. That is growth, not storage thrown
/// away, which is what this test is for.) SPCBPT is not included: its per-pass stage-1 and stage-2
/// alias tables and its reuse FIFOs' prefix boxes are allocated anew every pass (see
/// ARCHITECTURE.md).
///
/// Injected-bug check (done once, reverted): `PhaseBuffers::for_phase` building fresh
/// `ChunkOutput`s every call (dropping the old ones) makes every estimator here report
/// allocations.
#[test]
fn protocol_passes_do_not_allocate_in_steady_state() {
    use ember_core::estimators::PhaseBuffers;
    use ember_core::estimators::{EstimatorConfig, EstimatorKind, KernelChoice, LvcbptConfig, Renderer, SegmentAlgorithm, SegmentConfig};
    use ember_core::render::{Context, Film, render_pass};
    let (scene, geometry, _) = cornell_with_spheres(16, 16).build().unwrap();
    let tracer = BruteForce::new(geometry);
    let params = RenderParams { max_depth: MaxDepth::UNBOUNDED, seed: 3, ..RenderParams::default() };
    let ctx = Context { scene: &scene, tracer: &tracer };
    let configs = [
        EstimatorKind::Pt.default_config(),
        EstimatorKind::Lt.default_config(),
        EstimatorKind::Bdpt.default_config(),
        EstimatorConfig::Lvcbpt(LvcbptConfig { probe_paths: 500, ..LvcbptConfig::DEFAULT }),
        // Light paths, prefix sums, photons, grid and photon records reuse their storage.
        EstimatorKind::Ppm.default_config(),
        EstimatorKind::Bpm.default_config(),
        EstimatorKind::Vcm.default_config(),
        // Segment PT, LT and BDPT with the disk kernel: the kernels' streams live on the stack.
        EstimatorConfig::Segment(SegmentAlgorithm::PathTracing, SegmentConfig { kernel: KernelChoice::Disk, ..SegmentConfig::DEFAULT }),
        EstimatorConfig::Segment(SegmentAlgorithm::LightTracing, SegmentConfig { kernel: KernelChoice::Disk, ..SegmentConfig::DEFAULT }),
        EstimatorConfig::Segment(SegmentAlgorithm::Bidirectional, SegmentConfig { kernel: KernelChoice::Disk, ..SegmentConfig::DEFAULT }),
        // Path, photon and bidirectional filtering: see the next test.
    ];
    for config in configs {
        let mut renderer = Renderer::new(&scene, params, config).unwrap();
        let mut film = Film::new(16, 16);
        let mut buffers = PhaseBuffers::new();
        for pass in 0..12 {
            render_pass(&mut renderer, &ctx, &mut film, &mut buffers, pass);
        }
        let n = count_allocations(|| {
            for pass in 4..12 {
                render_pass(&mut renderer, &ctx, &mut film, &mut buffers, pass);
            }
        });
        assert_eq!(n, 0, "{:?}: {n} allocations in 8 replayed passes", config.kind());
        assert_eq!(film.passes(), 20);
    }
}

/// Path, photon and bidirectional filtering reuse their storage from pass to pass: the
/// nodes, grid, denominators, rows and propagated values, the chunk buffers and the
/// scratch. Unlike the estimators above, their buffers have no bound fixed by the film:
/// a pass holds as many nodes and row pairs as its paths happened to make. So a fresh
/// pass may still exceed every earlier one and grow a buffer (node phases keep a fixed
/// number of chunks and grow by a quarter more than they need, which makes that rare:
/// 5 and 4 allocations over 8 fresh 16×16 passes for MVF and BPF, none for PhF). The
/// test therefore replays passes whose high-water marks the warm-up has already
/// reached: any allocation is then storage thrown away and made anew.
///
/// Injected-bug checks (done once each, reverted): BPF's light-path scratch as fresh
/// `Vec`s per chunk (as it was before issue 16's fix: 16 allocations per pass) fails
/// here; so does `FilterPass::gather_rows` replacing the graph with
/// `FilterGraph::default()` instead of clearing it.
#[test]
fn filtering_passes_reuse_their_storage() {
    use ember_core::estimators::{EstimatorKind, PhaseBuffers, Renderer};
    use ember_core::render::{Context, Film, render_pass};
    let (scene, geometry, _) = cornell_with_spheres(16, 16).build().unwrap();
    let tracer = BruteForce::new(geometry);
    let params = RenderParams { max_depth: MaxDepth::UNBOUNDED, seed: 3, ..RenderParams::default() };
    let ctx = Context { scene: &scene, tracer: &tracer };
    for kind in [EstimatorKind::Mvf, EstimatorKind::Phf, EstimatorKind::Bpf] {
        let mut renderer = Renderer::new(&scene, params, kind.default_config()).unwrap();
        let mut film = Film::new(16, 16);
        let mut buffers = PhaseBuffers::new();
        for pass in 0..6 {
            render_pass(&mut renderer, &ctx, &mut film, &mut buffers, pass);
        }
        let n = count_allocations(|| {
            for pass in 0..6 {
                render_pass(&mut renderer, &ctx, &mut film, &mut buffers, pass);
            }
        });
        assert_eq!(n, 0, "{kind:?}: {n} allocations in 6 replayed passes");
        assert_eq!(film.passes(), 12);
    }
}
