//! The lane loop (`ember_core::transport::lanes`) renders the same image at every batch
//! width: PT, LT and their segment forms, on scenes with spheres of glass and rough
//! gold, Dirac lights and a window lit by the environment, at widths 1 (the scalar
//! reference: one path at a time, single-ray queries), 5, 16 and 32, compared pixel by
//! pixel (the film's exact sums), with the counters.
//!
//! The wrapper below answers batches through the brute-force tracer one ray at a time,
//! so only the loop differs between widths; it also counts the batches, so the test
//! fails if the loop never asked one of more than one ray (a width that is not used).
//!
//! PT's and LT's Lambertian vertices shade over lanes (`estimators::pt_lanes`,
//! `lt_lanes`) at every width above 1, and at every instruction set the lane kernels are compiled for
//! (`math::simd::Level`): the baseline, and AVX2 and AVX-512 where this machine has them.
//! Each is compared with width 1 at the baseline.
//!
//! Injected-bug checks (each done once, reverted), in `lanes::run_with_width`: a lane
//! reading the shadow answer at its own index (`occluded[k]` for
//! `occluded[shadow_of[k]]`): 243 of 1 024 pixels of PT differ at width 5; a lane given
//! another traced ray's hit once the batch has holes (`hits[lane_of[k] % n]` for
//! `hits[k]`): 27 of 1 024. In `pt_lanes` (PT on the Cornell box with spheres and Dirac
//! lights, width 5, first pass): a two-sided surface seen from the back not mirrored for
//! the BSDF sample (`d.z` for `-d.z`): 556 of 1 024 pixels differ; the MIS weight taken
//! as the balance heuristic's where the power heuristic is asked (`light_pdf /
//! (light_pdf + pdf)`): 559; a triangle light's density kept for lanes whose light is
//! not a triangle (`out.pdf[i] = l.pdf.0` without the select): 684. In `lt_lanes`: the
//! camera connection's value without β: 713 of 1 024 (the same scene); the adjoint's
//! shading-normal correction left out of the continuation's throughput, or of the
//! connection: 2 and 3 of 576 pixels of the window room with a smooth-shaded panel (the
//! only scene here whose shading normals differ from the geometric ones; the others
//! passed).

use std::cell::Cell;

use ember_core::bsdf::Material;
use ember_core::estimators::{EstimatorConfig, EstimatorKind, KernelChoice, SegmentAlgorithm, SegmentConfig};
use ember_core::geometry::{Ray, RayBatch, RayQuery, SurfaceHit};
use ember_core::math::Vec3;
use ember_core::math::simd::{Level, Set};
use ember_core::scene::SceneBuilder;
use ember_core::spectrum::Rgb;
use ember_core::transport::{Counters, Heuristic, RenderParams};
use ember_tests::render::Passes;
use ember_tests::scenes::{cornell_with_delta_lights, window_room};
use ember_tests::tracer::BruteForce;

/// The brute-force tracer at a given batch width, counting the rays asked in batches of
/// more than one.
struct AtWidth<'a> {
    inner: &'a BruteForce,
    width: usize,
    batched: Cell<u64>,
}

impl RayQuery for AtWidth<'_> {
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        self.inner.intersect(ray)
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.inner.occluded(ray)
    }
    fn batch_width(&self) -> usize {
        self.width
    }
    fn intersect_batch(&self, rays: RayBatch<'_>, hits: &mut [Option<SurfaceHit>]) {
        if rays.len() > 1 {
            self.batched.set(self.batched.get() + rays.len() as u64);
        }
        for (hit, ray) in hits.iter_mut().zip(rays.iter()) {
            *hit = self.inner.intersect(&ray);
        }
    }
    fn occluded_batch(&self, rays: RayBatch<'_>, occluded: &mut [bool]) {
        if rays.len() > 1 {
            self.batched.set(self.batched.get() + rays.len() as u64);
        }
        for (o, ray) in occluded.iter_mut().zip(rays.iter()) {
            *o = self.inner.occluded(&ray);
        }
    }
}

fn configs() -> Vec<(&'static str, EstimatorConfig)> {
    let segment = |algorithm| EstimatorConfig::Segment(algorithm, SegmentConfig { kernel: KernelChoice::Disk, ..SegmentConfig::DEFAULT });
    vec![
        ("pt", EstimatorKind::Pt.default_config()),
        ("lt", EstimatorKind::Lt.default_config()),
        ("spt (disk kernel)", segment(SegmentAlgorithm::PathTracing)),
        ("slt (disk kernel)", segment(SegmentAlgorithm::LightTracing)),
    ]
}

/// The lane kernels' levels this machine runs: the baseline, then AVX2 and AVX-512 where
/// detected.
fn levels() -> Vec<Level> {
    #[allow(unused_mut)]
    let mut levels = vec![Level::BASELINE];
    #[cfg(target_arch = "x86_64")]
    {
        let avx2 = ["avx2", "bmi1", "bmi2", "lzcnt", "popcnt"];
        let has = |f: &str| match f {
            "avx2" => std::arch::is_x86_feature_detected!("avx2"),
            "bmi1" => std::arch::is_x86_feature_detected!("bmi1"),
            "bmi2" => std::arch::is_x86_feature_detected!("bmi2"),
            "lzcnt" => std::arch::is_x86_feature_detected!("lzcnt"),
            "popcnt" => std::arch::is_x86_feature_detected!("popcnt"),
            "avx512f" => std::arch::is_x86_feature_detected!("avx512f"),
            "avx512vl" => std::arch::is_x86_feature_detected!("avx512vl"),
            "avx512bw" => std::arch::is_x86_feature_detected!("avx512bw"),
            "avx512dq" => std::arch::is_x86_feature_detected!("avx512dq"),
            _ => false,
        };
        if avx2.iter().all(|f| has(f)) {
            // SAFETY: the machine has every feature of the set (detected just above).
            #[allow(unsafe_code)]
            levels.push(unsafe { Level::assume(Set::Avx2) });
            if ["avx512f", "avx512vl", "avx512bw", "avx512dq"].iter().all(|f| has(f)) {
                // SAFETY: as above.
                #[allow(unsafe_code)]
                levels.push(unsafe { Level::assume(Set::Avx512) });
            }
        }
    }
    levels
}

fn check(name: &str, builder: SceneBuilder) {
    let (scene, geometry, _) = builder.build().unwrap();
    let tracer = BruteForce::new(geometry);
    for (estimator, config) in configs() {
        let render = |width: usize, simd: Level| {
            // The power heuristic, as every host renders PT (the default is the balance).
            let params = RenderParams { seed: 11, simd, heuristic: Heuristic::Power, ..RenderParams::default() };
            let at = AtWidth { inner: &tracer, width, batched: Cell::new(0) };
            let mut passes = Passes::new(&scene, &at, &params, config);
            let (image, counters) = (0..2).map(|pass| passes.pass_image(pass)).fold((Vec::new(), Vec::new()), |(mut i, mut c), (img, cnt)| {
                i.push(img);
                c.push(cnt);
                (i, c)
            });
            (image, counters, at.batched.get())
        };
        let (reference, counters, batched) = render(1, Level::BASELINE);
        assert_eq!(batched, 0, "{name} {estimator}: width 1 asked batches");
        for simd in levels() {
            for width in [5, 16, 32] {
                let (image, c, batched) = render(width, simd);
                let at = format!("{name} {estimator}: width {width}, {} lane kernels", simd.name());
                assert!(batched > 0, "{at}: never asked a batch");
                for (pass, (a, b)) in reference.iter().zip(&image).enumerate() {
                    let differ = a.iter().zip(b).filter(|(x, y)| x != y).count();
                    assert_eq!(differ, 0, "{at}: pass {pass}: {differ} of {} pixels differ from width 1", a.len());
                }
                // The lane loop's own counts depend on the width (steps, slots, lanes
                // shaded over lanes); the arrivals (busy lane-steps) do not, and
                // everything else must be the same.
                let work = |c: &[Counters]| c.iter().map(|c| Counters { lanes: Default::default(), ..*c }).collect::<Vec<_>>();
                assert_eq!(work(&counters), work(&c), "{at}: counters");
                for (a, b) in counters.iter().zip(&c) {
                    assert_eq!(a.lanes.busy, b.lanes.busy, "{at}: arrivals");
                    assert!(b.lanes.busy <= b.lanes.slots && b.lanes.slots.is_multiple_of(b.lanes.steps.max(1)), "{at}: {:?}", b.lanes);
                }
            }
        }
    }
}

/// The window room with a diffuse panel whose vertex normals lean away from its plane:
/// shading normals unlike the geometric one, so the adjoint's shading-normal correction
/// (light tracing) is not 1.
fn window_room_with_smooth_panel() -> SceneBuilder {
    let mut b = window_room(24, 24);
    let panel = b.add_material(Material::diffuse(Rgb::new(0.6, 0.7, 0.5)));
    let p = [Vec3::new(-1.0, 0.2, -0.8), Vec3::new(0.6, 0.3, -1.2), Vec3::new(-0.2, 1.6, -1.0)];
    let n = [Vec3::new(0.3, 0.1, 1.0).normalize(), Vec3::new(-0.4, 0.2, 1.0).normalize(), Vec3::new(0.1, -0.5, 1.0).normalize()];
    b.add_triangle(p, Some(n), panel, None);
    b
}

#[test]
fn images_are_the_same_at_every_lane_width() {
    check("cornell with spheres and Dirac lights", cornell_with_delta_lights(32, 32));
    check("window room", window_room(24, 24));
    check("window room with a smooth-shaded panel", window_room_with_smooth_panel());
}
