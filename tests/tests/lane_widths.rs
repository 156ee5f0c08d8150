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
//! Injected-bug checks (each done once, reverted), in `lanes::run_with_width`: a lane
//! reading the shadow answer at its own index (`occluded[k]` for
//! `occluded[shadow_of[k]]`): 243 of 1 024 pixels of PT differ at width 5; a lane given
//! another traced ray's hit once the batch has holes (`hits[lane_of[k] % n]` for
//! `hits[k]`): 27 of 1 024.

use std::cell::Cell;

use ember_core::estimators::{EstimatorConfig, EstimatorKind, KernelChoice, SegmentAlgorithm, SegmentConfig};
use ember_core::geometry::{Ray, RayBatch, RayQuery, SurfaceHit};
use ember_core::scene::SceneBuilder;
use ember_core::transport::RenderParams;
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

fn check(name: &str, builder: SceneBuilder) {
    let (scene, geometry, _) = builder.build().unwrap();
    let tracer = BruteForce::new(geometry);
    let params = RenderParams { seed: 11, ..RenderParams::default() };
    for (estimator, config) in configs() {
        let render = |width: usize| {
            let at = AtWidth { inner: &tracer, width, batched: Cell::new(0) };
            let mut passes = Passes::new(&scene, &at, &params, config);
            let (image, counters) = (0..2).map(|pass| passes.pass_image(pass)).fold((Vec::new(), Vec::new()), |(mut i, mut c), (img, cnt)| {
                i.push(img);
                c.push(cnt);
                (i, c)
            });
            (image, counters, at.batched.get())
        };
        let (reference, counters, batched) = render(1);
        assert_eq!(batched, 0, "{name} {estimator}: width 1 asked batches");
        for width in [5, 16, 32] {
            let (image, c, batched) = render(width);
            assert!(batched > 0, "{name} {estimator}: width {width} never asked a batch");
            for (pass, (a, b)) in reference.iter().zip(&image).enumerate() {
                let differ = a.iter().zip(b).filter(|(x, y)| x != y).count();
                assert_eq!(differ, 0, "{name} {estimator}: pass {pass} at width {width}: {differ} of {} pixels differ from width 1", a.len());
            }
            assert_eq!(counters, c, "{name} {estimator}: counters at width {width}");
        }
    }
}

#[test]
fn images_are_the_same_at_every_lane_width() {
    check("cornell with spheres and Dirac lights", cornell_with_delta_lights(32, 32));
    check("window room", window_room(24, 24));
}
