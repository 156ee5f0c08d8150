//! The lane loop: many paths stepped together, their ray queries asked in batches.
//!
//! # Why
//!
//! A path tracer that walks one path at a time asks the accelerator one ray, shades one
//! vertex, asks one shadow ray, and so on: every query starts cold, and nothing lets the
//! tracer work on several rays at once. Mitsuba 3's vectorised backends and the
//! lane-parallel CPU designs (Áfra et al., HPG 2016; MoonRay, HPG 2017) instead keep a
//! *batch* of paths in flight and run each step over all of them: all trace, all shade,
//! all test their shadow rays, all scatter. This module is that loop. It owns no
//! transport: an estimator describes what happens to one path at each step (a
//! [`LaneProgram`]), and [`run`] keeps as many of them in flight as the tracer asks
//! ([`RayQuery::batch_width`], at most [`LANES`]) over a range of work items (pixels,
//! light paths).
//!
//! # Width
//!
//! Batching pays only where something works on the batch as a whole: a tracer with
//! packet or stream queries, a C caller whose callback costs a crossing per call, and
//! lane-wise shading ([`LaneProgram::arrive_batch`]: PT's and LT's Lambertian vertices,
//! `estimators::pt_lanes`, `lt_lanes`). Measured on the built-in box with our BVH4
//! answering one ray at a time and nothing shaded over lanes, 32 paths in flight cost
//! PT 10 % more instructions and 19 % more time than one (more stores and loads of path
//! state, 16 % more mispredicted branches: docs/performance.md). So [`run`] keeps the
//! tracer's width (1 for our BVH4: one path at a time through the same steps with
//! single-ray queries, the reference for every width), and PT and LT ask
//! [`run_with_width`] for 16 where their lane kernels run on AVX2 or AVX-512
//! (`math::simd::Level::paths_in_flight`).
//!
//! # The steps
//!
//! For every live lane, in lane order:
//!
//! 1. **Refill.** An empty lane takes the next work item ([`LaneProgram::start`]); an
//!    item that ends before its first ray (a camera sample outside the image, depth 0)
//!    records its result there and the lane takes the next one. Unlike a fixed group of
//!    paths that waits for its longest member (Mitsuba's), a finished lane is busy again
//!    at the next step, so lanes idle only at the end of the range.
//! 2. **Trace.** The live lanes' rays ([`LaneProgram::ray`]) go to the tracer in one
//!    [`RayQuery::intersect_batch`].
//! 3. **Arrive.** Each lane records what its vertex gives ([`LaneProgram::arrive`]): the
//!    emission found, a next-event or camera-connection sample, the BSDF draw that
//!    continues it. A sample that needs a visibility test returns its shadow ray.
//! 4. **Test.** All shadow rays of the step go in one [`RayQuery::occluded_batch`].
//! 5. **Leave.** Each lane that arrived learns its shadow ray's answer
//!    ([`LaneProgram::leave`]) and says whether its path goes on; one that ends records
//!    its result ([`LaneProgram::finish`]) and its lane is refilled at the next step.
//!
//! # Determinism
//!
//! A path's random numbers come from its own counter-based stream (seed, item, pass,
//! dimension), and its arithmetic is the same whichever lanes run beside it or in which
//! order the steps visit them; the film's sums are exact integers (`render::film`). So
//! the images do not depend on the batch width (`tests/tests/lane_widths.rs` compares
//! widths 1, 5, 16 and 32 pixel by pixel), and every estimator on this loop renders bit
//! for bit as it did when it walked one path at a time (the image hashes,
//! `host-cli/tests/image_hashes.rs`).
//!
//! # Occupancy
//!
//! [`run`] reports its steps and the lanes that did work in them ([`LaneStats`]): the
//! share of lane-steps doing work, which only the tail of a range (the last paths
//! finishing while no item is left to refill with) lowers.
//!
//! Nothing here allocates: the batch lives on the stack, [`LANES`] paths and their rays.

use core::ops::Range;

use crate::geometry::{Ray, RayBatch, RayQuery, SurfaceHit};

/// Paths in flight per batch.
pub use crate::math::soa::LANES;

/// What a path does at each step of the lane loop (see the module notes).
pub trait LaneProgram {
    /// A path in flight: everything it carries from one step to the next.
    type Path;

    /// Start the path of work item `item`; `None` if it ends before its first
    /// closest-hit ray (having recorded its result).
    fn start(&mut self, item: u32) -> Option<Self::Path>;

    /// The ray the path traces next.
    fn ray(&self, path: &Self::Path) -> Ray;

    /// The path's ray reached `hit` (`None`: it escaped). Record the vertex and draw the
    /// next direction; the shadow ray to test before the path leaves, if any.
    fn arrive(&mut self, path: &mut Self::Path, hit: Option<SurfaceHit>) -> Arrival;

    /// [`Self::arrive`] for the traced lanes of one step at once: lane `lane_of[k]` of
    /// `lanes` reached `hits[k]`, its arrival goes to `arrivals[k]`. A program that shades
    /// over lanes overrides it; the default arrives lane by lane, in order.
    fn arrive_batch(&mut self, lanes: &mut [Option<Self::Path>], lane_of: &[u8], hits: &[Option<SurfaceHit>], arrivals: &mut [Arrival]) {
        arrive_each(self, lanes, lane_of, hits, arrivals);
    }

    /// The shadow ray asked by [`Self::arrive`] was `occluded` (`None` if none was
    /// asked). True if the path goes on.
    fn leave(&mut self, path: &mut Self::Path, arrival: Arrival, occluded: Option<bool>) -> bool;

    /// The path ended: record its result.
    fn finish(&mut self, path: Self::Path);
}

/// [`LaneProgram::arrive_batch`] lane by lane, in order: its default, and what an
/// override does for the steps it does not shade over lanes.
pub fn arrive_each<P: LaneProgram + ?Sized>(
    program: &mut P,
    lanes: &mut [Option<P::Path>],
    lane_of: &[u8],
    hits: &[Option<SurfaceHit>],
    arrivals: &mut [Arrival],
) {
    for (k, hit) in hits.iter().enumerate() {
        let path = lanes[lane_of[k] as usize].as_mut().expect("a traced lane holds a path");
        arrivals[k] = program.arrive(path, *hit);
    }
}

/// What [`LaneProgram::arrive`] asks of the rest of the step.
#[derive(Clone, Copy, Debug)]
pub struct Arrival {
    /// A shadow ray to test before leaving.
    pub shadow: Option<Ray>,
    /// The path has a next ray (it may still end in [`LaneProgram::leave`]).
    pub continues: bool,
}

/// Steps of a [`run`] and the lane-steps that traced a ray.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct LaneStats {
    /// Steps (batches traced).
    pub steps: u64,
    /// Lanes with a path, summed over steps: every one an arrival.
    pub busy: u64,
    /// Lanes in flight (the width), summed over steps.
    pub slots: u64,
    /// Arrivals shaded by a program's lane kernels ([`LaneProgram::arrive_batch`]),
    /// the rest having been shaded one path at a time. A program counts these itself.
    pub shaded: u64,
}

impl LaneStats {
    /// The share of lane-steps doing work.
    pub fn occupancy(&self) -> f64 {
        if self.slots == 0 { 1.0 } else { self.busy as f64 / self.slots as f64 }
    }

    /// The share of arrivals shaded over lanes.
    pub fn shaded_share(&self) -> f64 {
        if self.busy == 0 { 0.0 } else { self.shaded as f64 / self.busy as f64 }
    }

    /// Paths in flight per step (the width the loop ran at; 0 before any step).
    pub fn width(&self) -> u64 {
        self.slots.checked_div(self.steps).unwrap_or(0)
    }
}

impl core::ops::AddAssign for LaneStats {
    fn add_assign(&mut self, o: Self) {
        self.steps += o.steps;
        self.busy += o.busy;
        self.slots += o.slots;
        self.shaded += o.shaded;
    }
}

/// Up to [`LANES`] rays in structure-of-arrays form.
struct Rays {
    origin: [[f32; LANES]; 3],
    dir: [[f32; LANES]; 3],
    t_max: [f32; LANES],
    len: usize,
}

impl Rays {
    fn new() -> Self {
        Self { origin: [[0.0; LANES]; 3], dir: [[0.0; LANES]; 3], t_max: [0.0; LANES], len: 0 }
    }

    #[inline]
    fn push(&mut self, ray: &Ray) {
        let i = self.len;
        for a in 0..3 {
            self.origin[a][i] = ray.origin[a];
            self.dir[a][i] = ray.dir[a];
        }
        self.t_max[i] = ray.t_max;
        self.len += 1;
    }

    fn batch(&self) -> RayBatch<'_> {
        let n = self.len;
        RayBatch {
            origin: [&self.origin[0][..n], &self.origin[1][..n], &self.origin[2][..n]],
            dir: [&self.dir[0][..n], &self.dir[1][..n], &self.dir[2][..n]],
            t_max: &self.t_max[..n],
        }
    }
}

/// Run `program` over the work items `items`, [`LANES`] paths at a time (see the
/// module notes).
pub fn run<P: LaneProgram, Q: RayQuery + ?Sized>(program: &mut P, tracer: &Q, items: Range<u32>) -> LaneStats {
    run_with_width(program, tracer, items, tracer.batch_width())
}

/// [`run`] with `width` paths in flight (clamped to 1..=[`LANES`]).
pub fn run_with_width<P: LaneProgram, Q: RayQuery + ?Sized>(program: &mut P, tracer: &Q, items: Range<u32>, width: usize) -> LaneStats {
    let width = width.clamp(1, LANES);
    let mut stats = LaneStats::default();
    if width == 1 {
        // The scalar width: one path at a time through the same steps, single-ray queries.
        for item in items {
            if let Some(path) = program.start(item) {
                let path = walk(program, tracer, path, &mut stats);
                program.finish(path);
            }
        }
        return stats;
    }
    let mut lanes: [Option<P::Path>; LANES] = core::array::from_fn(|_| None);
    let mut next = items.start;
    let mut rays = Rays::new();
    let mut shadows = Rays::new();
    // Per traced ray: its lane; its hit; its arrival and shadow-ray slot.
    let mut lane_of = [0u8; LANES];
    let mut hits = [None; LANES];
    let mut arrivals = [Arrival { shadow: None, continues: false }; LANES];
    let mut shadow_of = [u8::MAX; LANES];
    let mut occluded = [false; LANES];
    loop {
        // 1. Refill empty lanes and gather the rays.
        rays.len = 0;
        for (i, lane) in lanes[..width].iter_mut().enumerate() {
            while lane.is_none() && next < items.end {
                *lane = program.start(next);
                next += 1;
            }
            if let Some(path) = lane {
                lane_of[rays.len] = i as u8;
                rays.push(&program.ray(path));
            }
        }
        let n = rays.len;
        if n == 0 {
            return stats;
        }
        stats.steps += 1;
        stats.busy += n as u64;
        stats.slots += width as u64;

        // 2. Trace.
        tracer.intersect_batch(rays.batch(), &mut hits[..n]);

        // 3. Arrive; gather the shadow rays.
        program.arrive_batch(&mut lanes[..width], &lane_of[..n], &hits[..n], &mut arrivals[..n]);
        shadows.len = 0;
        for k in 0..n {
            shadow_of[k] = match &arrivals[k].shadow {
                Some(ray) => {
                    shadows.push(ray);
                    (shadows.len - 1) as u8
                }
                None => u8::MAX,
            };
        }

        // 4. Test them.
        if shadows.len > 0 {
            tracer.occluded_batch(shadows.batch(), &mut occluded[..shadows.len]);
        }

        // 5. Leave; finish the paths that end.
        for k in 0..n {
            let lane = &mut lanes[lane_of[k] as usize];
            let path = lane.as_mut().expect("a traced lane holds a path");
            let answer = (shadow_of[k] != u8::MAX).then(|| occluded[shadow_of[k] as usize]);
            if !program.leave(path, arrivals[k], answer)
                && let Some(path) = lane.take()
            {
                program.finish(path);
            }
        }
    }
}

/// The same steps for one path with single-ray queries: what a caller that needs one
/// path's result at once (not a range of items) uses, with the program's own steps.
pub fn run_one<P: LaneProgram, Q: RayQuery + ?Sized>(program: &mut P, tracer: &Q, path: P::Path) -> P::Path {
    walk(program, tracer, path, &mut LaneStats::default())
}

/// One path's steps until it ends, one ray at a time.
#[inline(always)]
fn walk<P: LaneProgram, Q: RayQuery + ?Sized>(program: &mut P, tracer: &Q, mut path: P::Path, stats: &mut LaneStats) -> P::Path {
    loop {
        stats.steps += 1;
        stats.busy += 1;
        stats.slots += 1;
        let hit = tracer.intersect(&program.ray(&path));
        let arrival = program.arrive(&mut path, hit);
        let answer = arrival.shadow.map(|ray| tracer.occluded(&ray));
        if !program.leave(&mut path, arrival, answer) {
            return path;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use alloc::vec;
    use alloc::vec::Vec;

    /// A tracer that hits nothing and calls a shadow ray occluded when its origin's x is
    /// odd: each lane's answer can be told from its own ray.
    struct OddBlocks;

    impl RayQuery for OddBlocks {
        fn intersect(&self, _: &Ray) -> Option<SurfaceHit> {
            None
        }
        fn occluded(&self, ray: &Ray) -> bool {
            ray.origin.x as u32 % 2 == 1
        }
    }

    /// Item i: ends at its start if i % 5 == 0, else takes i % 7 + 1 steps, asking a
    /// shadow ray (origin x = i + step) on every other step.
    struct Toy {
        started: Vec<u32>,
        finished: Vec<u32>,
        traced: u64,
    }

    struct ToyPath {
        item: u32,
        step: u32,
    }

    impl LaneProgram for Toy {
        type Path = ToyPath;
        fn start(&mut self, item: u32) -> Option<ToyPath> {
            self.started[item as usize] += 1;
            if item.is_multiple_of(5) {
                self.finished[item as usize] += 1;
                return None;
            }
            Some(ToyPath { item, step: 0 })
        }
        fn ray(&self, p: &ToyPath) -> Ray {
            Ray::new(Vec3::new(p.item as f32, 0.0, 0.0), Vec3::X, 1.0)
        }
        fn arrive(&mut self, p: &mut ToyPath, hit: Option<SurfaceHit>) -> Arrival {
            assert!(hit.is_none());
            self.traced += 1;
            let shadow = p.step.is_multiple_of(2).then(|| Ray::new(Vec3::new((p.item + p.step) as f32, 0.0, 0.0), Vec3::Y, 1.0));
            Arrival { shadow, continues: p.step < p.item % 7 }
        }
        fn leave(&mut self, p: &mut ToyPath, arrival: Arrival, occluded: Option<bool>) -> bool {
            // The answer is this lane's own shadow ray's (a mix-up of lanes shows here).
            let expected = p.step.is_multiple_of(2).then_some((p.item + p.step) % 2 == 1);
            assert_eq!(occluded, expected, "item {} step {}", p.item, p.step);
            p.step += 1;
            arrival.continues
        }
        fn finish(&mut self, p: ToyPath) {
            assert_eq!(p.step, p.item % 7 + 1, "item {} finished early or late", p.item);
            self.finished[p.item as usize] += 1;
        }
    }

    /// Every item starts once and finishes once, each lane gets its own shadow answer, and
    /// the steps show the lanes refilled: around the batch width, for an empty range and
    /// for ranges not starting at 0. Seen to fail on two injected bugs: a lane reading
    /// the answer at its own index instead of its shadow ray's (`occluded[k]`), and the
    /// refill taking one item per empty lane per step (`while` → `if`, so an item that
    /// ends at its start leaves its lane idle for a step: too many steps).
    #[test]
    fn every_item_runs_once_with_its_own_answers() {
        for width in [1, 7, LANES] {
            for (start, n) in [(0u32, 0u32), (0, 1), (3, 31), (0, 32), (7, 33), (0, 100), (5, 1000)] {
                let end = start + n;
                let mut toy = Toy { started: vec![0; end as usize], finished: vec![0; end as usize], traced: 0 };
                let stats = run_with_width(&mut toy, &OddBlocks, start..end, width);
                for i in start..end {
                    assert_eq!((toy.started[i as usize], toy.finished[i as usize]), (1, 1), "item {i} of {start}..{end}");
                }
                assert!(toy.started[..start as usize].iter().all(|&s| s == 0));
                let expected: u64 = (start..end).filter(|i| i % 5 != 0).map(|i| (i % 7 + 1) as u64).sum();
                assert_eq!((stats.busy, toy.traced), (expected, expected));
                // Lanes refill: only the tail of the range leaves lanes empty, so the
                // steps are at most the longest path (7) past the full batches' count.
                assert!(stats.steps <= expected.div_ceil(width as u64) + 7, "{stats:?}");
                assert_eq!(stats.slots, stats.steps * width as u64);
                assert!(stats.occupancy() > 0.0 && stats.occupancy() <= 1.0);
            }
        }
    }
}
