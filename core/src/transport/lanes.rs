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
//! [`LaneProgram`]), and [`run`] keeps up to [`LANES`] of them in flight over a range of
//! work items (pixels, light paths).
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
//! the images do not depend on the batch width: the scalar width (one lane) is the same
//! loop, and every estimator on this loop renders bit for bit as it did when it walked one
//! path at a time (the image hashes, `host-cli/tests/image_hashes.rs`).
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
pub const LANES: usize = 32;

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

    /// The shadow ray asked by [`Self::arrive`] was `occluded` (`None` if none was
    /// asked). True if the path goes on.
    fn leave(&mut self, path: &mut Self::Path, arrival: Arrival, occluded: Option<bool>) -> bool;

    /// The path ended: record its result.
    fn finish(&mut self, path: Self::Path);
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
pub struct LaneStats {
    /// Steps (batches traced).
    pub steps: u64,
    /// Lanes with a path, summed over steps.
    pub busy: u64,
}

impl LaneStats {
    /// The share of lane-steps doing work, at `LANES` lanes per step.
    pub fn occupancy(&self) -> f64 {
        if self.steps == 0 { 1.0 } else { self.busy as f64 / (self.steps * LANES as u64) as f64 }
    }
}

impl core::ops::AddAssign for LaneStats {
    fn add_assign(&mut self, o: Self) {
        self.steps += o.steps;
        self.busy += o.busy;
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
    let mut stats = LaneStats::default();
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
        for (i, lane) in lanes.iter_mut().enumerate() {
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

        // 2. Trace.
        tracer.intersect_batch(rays.batch(), &mut hits[..n]);

        // 3. Arrive; gather the shadow rays.
        shadows.len = 0;
        for k in 0..n {
            let path = lanes[lane_of[k] as usize].as_mut().expect("a traced lane holds a path");
            let arrival = program.arrive(path, hits[k]);
            shadow_of[k] = match &arrival.shadow {
                Some(ray) => {
                    shadows.push(ray);
                    (shadows.len - 1) as u8
                }
                None => u8::MAX,
            };
            arrivals[k] = arrival;
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
            if !program.leave(path, arrivals[k], answer) {
                if let Some(path) = lane.take() {
                    program.finish(path);
                }
            }
        }
    }
}

/// The same steps for one path with single-ray queries: what a caller that needs one
/// path's result at once (not a range of items) uses, with the program's own steps.
pub fn run_one<P: LaneProgram, Q: RayQuery + ?Sized>(program: &mut P, tracer: &Q, mut path: P::Path) -> P::Path {
    loop {
        let hit = tracer.intersect(&program.ray(&path));
        let arrival = program.arrive(&mut path, hit);
        let answer = arrival.shadow.map(|ray| tracer.occluded(&ray));
        if !program.leave(&mut path, arrival, answer) {
            return path;
        }
    }
}
