//! The render protocol: one way for every host to drive every estimator.
//!
//! An estimator's whole work, preprocessing included, is a sequence of **phases**. A
//! phase is a map over an index range `0..items` (light paths, pixels, training records,
//! eye subspaces), cut into chunks of a size the estimator fixes, followed by a
//! **reduction** the estimator owns, which takes the chunks' outputs in index order:
//!
//! ```text
//! loop { phase = est.next_phase()?;                          // what to map next
//!        for chunk in phase.chunks() { est.map(ctx, phase, chunk, &mut out[c]) }   // any thread
//!        est.reduce(ctx, phase, &mut out, film) }             // one thread, index order
//! ```
//!
//! Phases before [`Phased::start_pass`] was first called are the estimator's setup (SPCBPT's
//! κ_L → dataset → κ_E → Q → dataset → Adam, LVCBPT's c̄ probe); after `start_pass(p)` they
//! are pass p's (LVCBPT: light paths → camera; SPCBPT: light paths → Γ tables → splats →
//! camera). The last phase of a pass commits it to the [`Film`] with the pass's splat
//! factor. Each estimator's phase order lives in its own module, once.
//!
//! **Determinism.** Random numbers derive from (seed, index, pass, dimension) and the
//! chunk sizes do not depend on the host, so a host that maps chunks on any number of
//! threads (or address spaces) and hands the outputs to `reduce` in chunk order gets the
//! same bits as [`run_phases`], the serial runner the tests and thread-less hosts use.
//!
//! **Plain data.** A chunk's output ([`ChunkOutput`]) is vectors of plain values (camera
//! samples, splats, light vertices, feature vectors, sums, training records): a host can
//! copy it between address spaces. The reduced state a later phase reads is a function of
//! those outputs alone, so a host without shared memory hands every worker the same
//! outputs and lets each reduce them.
//!
//! **Allocation.** Hosts keep one [`PhaseBuffers`] across passes: a chunk's output is
//! cleared and refilled in place, so its vectors keep their capacity from pass to pass.

#![warn(missing_docs)]

pub mod aov;
mod film;
#[cfg(feature = "wire")]
pub mod wire;

/// What every phase reads: the scene and the ray queries (defined with the scene).
pub use crate::scene::Context;
pub use film::{Band, Film, FilmError, ParallelBands, QUANTUM_BITS, Tallies, WeightedSum};

use alloc::vec::Vec;
use core::ops::Range;

use crate::geometry::RayQuery;
use crate::spectrum::Rgb;
use crate::transport::{Counters, Splat};

/// An estimator's own chunk data ([`Phased::Data`]): plain values, cleared in place so
/// its buffers keep their capacity from pass to pass.
pub trait Payload: Default + Clone + core::fmt::Debug {
    /// Empty every buffer, keeping its capacity.
    fn clear(&mut self);
}

/// Nothing beyond camera samples, splats and counters.
impl Payload for () {
    fn clear(&mut self) {}
}

/// Pixels per chunk of a camera phase, light paths per chunk of a light phase, for a
/// phase of `items`: about [`CHUNKS`] chunks, a power of two from 64 to 1024 items each.
/// A pass ends when its slowest thread does, so chunks must be many per thread: 1024
/// items gave the 256² suite scenes 64 chunks, 4 per thread on 16 threads, where path
/// tracing scaled to 10.8× (docs/performance.md, "Thread scaling on 16 cores"). The
/// size depends on the phase alone, never on the host, and the random numbers on the
/// item alone, so the image does not depend on it either.
pub fn chunk_for(items: u32) -> u32 {
    (items / CHUNKS).max(1).next_power_of_two().clamp(64, 1024)
}

/// The chunks a large phase is cut into ([`chunk_for`]).
pub const CHUNKS: u32 = 256;

/// One phase: a map over `0..items` in chunks of `chunk`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Phase {
    /// What it does, for progress reports and timing tables.
    pub name: &'static str,
    /// Its number in the estimator's schedule, stable across passes (hosts key
    /// [`PhaseBuffers`] by it).
    pub id: u8,
    /// The pass it belongs to; `None` during setup.
    pub pass: Option<u32>,
    /// Items to map: `0..items`.
    pub items: u32,
    /// Items per chunk (fixed by the estimator, never by the host).
    pub chunk: u32,
    /// Do the items count as samples (camera samples, light paths) in throughput reports?
    pub samples: bool,
}

impl Phase {
    /// Number of chunks.
    pub fn chunk_count(&self) -> usize {
        self.items.div_ceil(self.chunk.max(1)) as usize
    }
    /// The index range of chunk `c`.
    pub fn chunk_range(&self, c: usize) -> Range<u32> {
        let chunk = self.chunk.max(1);
        let start = (c as u32).saturating_mul(chunk).min(self.items);
        start..start.saturating_add(chunk).min(self.items)
    }
}

/// What mapping one chunk produced. Plain data; cleared and refilled in place.
#[derive(Clone, Debug, Default)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct ChunkOutput<D> {
    /// The chunk's index range.
    pub items: Range<u32>,
    /// One camera sample per item (pixel phases).
    pub pixels: Vec<Rgb>,
    /// Splats, in emission order.
    pub splats: Vec<Splat>,
    /// Work counters.
    pub counters: Counters,
    /// Estimator-specific output: the estimator's own type ([`Phased::Data`]).
    pub data: D,
}

impl<D: Payload> ChunkOutput<D> {
    /// Clear for a new map over `items`, keeping every buffer's capacity.
    pub fn reset(&mut self, items: Range<u32>) {
        self.items = items;
        self.pixels.clear();
        self.splats.clear();
        self.counters = Counters::default();
        self.data.clear();
    }

    /// The camera-sample buffer sized to the chunk (zeroed).
    pub fn pixel_buffer(&mut self) -> &mut [Rgb] {
        self.pixels.clear();
        self.pixels.resize(self.items.len(), Rgb::ZERO);
        &mut self.pixels
    }

    /// The pixel buffer (as [`Self::pixel_buffer`]) and the splats, for estimators that
    /// write both (BDPT's t = 1 strategies).
    pub fn pixels_and_splats(&mut self) -> (&mut [Rgb], &mut Vec<Splat>) {
        self.pixel_buffer();
        (&mut self.pixels, &mut self.splats)
    }
}

/// Chunk outputs kept across phases and passes, one list per phase id.
#[derive(Clone, Debug)]
pub struct PhaseBuffers<D> {
    lists: Vec<Vec<ChunkOutput<D>>>,
}

impl<D> Default for PhaseBuffers<D> {
    fn default() -> Self {
        Self { lists: Vec::new() }
    }
}

impl<D: Payload> PhaseBuffers<D> {
    /// No buffers yet.
    pub fn new() -> Self {
        Self::default()
    }
    /// The outputs for `phase`, one per chunk, each reset to its chunk's range.
    pub fn for_phase(&mut self, phase: &Phase) -> &mut [ChunkOutput<D>] {
        let outputs = self.outputs(phase);
        for (c, out) in outputs.iter_mut().enumerate() {
            out.reset(phase.chunk_range(c));
        }
        outputs
    }
    /// The outputs for `phase` as they stand: what [`Self::for_phase`] reset and the host
    /// filled since (a host that receives chunk outputs one message at a time).
    pub fn outputs(&mut self, phase: &Phase) -> &mut [ChunkOutput<D>] {
        let id = phase.id as usize;
        if self.lists.len() <= id {
            self.lists.resize_with(id + 1, Vec::new);
        }
        let list = &mut self.lists[id];
        let n = phase.chunk_count();
        if list.len() < n {
            list.resize_with(n, ChunkOutput::default);
        }
        &mut list[..n]
    }
}

/// What an estimator implements to be driven phase by phase (see the module notes).
pub trait Phased<Q: RayQuery + ?Sized> {
    /// What a chunk carries beyond camera samples, splats and counters: the estimator's
    /// own plain data.
    type Data: Payload;
    /// The phase to map next, or `None` when nothing is pending (setup is done and the
    /// last started pass is committed).
    fn next_phase(&self) -> Option<Phase>;
    /// Queue pass `pass`: its phases follow any pending setup phases.
    fn start_pass(&mut self, pass: u32);
    /// Map `phase` over `out.items` into `out` (which [`PhaseBuffers::for_phase`] reset).
    fn map(&self, ctx: &Context<'_, Q>, phase: &Phase, out: &mut ChunkOutput<Self::Data>);
    /// Reduce the phase's outputs, given in chunk order, into the estimator's state and
    /// the film; advances to the next phase.
    fn reduce(&mut self, ctx: &Context<'_, Q>, phase: &Phase, outputs: &mut [ChunkOutput<Self::Data>], film: &mut Film);
    /// Queue only those phases of pass `pass` that carry state into later passes, and
    /// nothing that touches the film: how a render that starts at a later pass (one task
    /// of a split render, docs/distributed.md) reaches the state a render from pass 0
    /// holds there. Returns false, queueing nothing, when the estimator carries nothing
    /// from one pass to the next, which is the default and true of every estimator but
    /// SPCBPT with reuse (its FIFOs of earlier passes' light vertices).
    fn replay_pass(&mut self, pass: u32) -> bool {
        let _ = pass;
        false
    }
}

/// Where an estimator stands in its schedule of `setup` setup phases and `pass` phases
/// per pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cursor {
    setup: u8,
    per_pass: u8,
    state: CursorState,
    /// A pass queued behind pending setup, with the phases it runs.
    queued: Option<(u32, u8)>,
    /// Phases the current pass runs: `per_pass`, or fewer when it is replayed.
    runs: u8,
}

/// A position in a schedule.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Setup phase i.
    Setup(u8),
    /// Phase i of a pass.
    Pass(u32, u8),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum CursorState {
    At(Stage),
    Idle,
}

impl Cursor {
    /// A schedule of `setup` setup phases, then `per_pass` phases in every pass.
    pub fn new(setup: u8, per_pass: u8) -> Self {
        let state = if setup > 0 { CursorState::At(Stage::Setup(0)) } else { CursorState::Idle };
        Self { setup, per_pass, state, queued: None, runs: per_pass }
    }
    /// The pending stage, if any.
    pub fn stage(&self) -> Option<Stage> {
        match self.state {
            CursorState::At(s) => Some(s),
            CursorState::Idle => None,
        }
    }
    /// Queue pass `pass` (after setup, if setup is still pending).
    pub fn start_pass(&mut self, pass: u32) {
        self.queue(pass, self.per_pass);
    }
    /// Queue the first `phases` phases of pass `pass` only (a replay: its end is not the
    /// end of a pass, so [`Cursor::advance`] never reports it).
    pub fn start_replay(&mut self, pass: u32, phases: u8) {
        self.queue(pass, phases.min(self.per_pass));
    }
    fn queue(&mut self, pass: u32, runs: u8) {
        match self.state {
            CursorState::At(Stage::Setup(_)) => self.queued = Some((pass, runs)),
            _ if runs > 0 => {
                self.state = CursorState::At(Stage::Pass(pass, 0));
                self.runs = runs;
            }
            _ => {}
        }
    }
    /// Move past the current stage; returns true when that ended a pass.
    pub fn advance(&mut self) -> bool {
        match self.state {
            CursorState::At(Stage::Setup(i)) if i + 1 < self.setup => {
                self.state = CursorState::At(Stage::Setup(i + 1));
                false
            }
            CursorState::At(Stage::Setup(_)) => {
                self.state = CursorState::Idle;
                if let Some((p, runs)) = self.queued.take() {
                    self.queue(p, runs);
                }
                false
            }
            CursorState::At(Stage::Pass(p, i)) if i + 1 < self.runs => {
                self.state = CursorState::At(Stage::Pass(p, i + 1));
                false
            }
            CursorState::At(Stage::Pass(..)) => {
                self.state = CursorState::Idle;
                self.runs == self.per_pass
            }
            CursorState::Idle => false,
        }
    }
}

/// The serial runner: map and reduce every pending phase in order on this thread.
/// Returns the summed counters and the items of phases that count as samples.
pub fn run_phases<Q: RayQuery + ?Sized, E: Phased<Q> + ?Sized>(
    est: &mut E,
    ctx: &Context<'_, Q>,
    film: &mut Film,
    buffers: &mut PhaseBuffers<E::Data>,
) -> (Counters, u64) {
    let mut counters = Counters::default();
    let mut samples = 0u64;
    while let Some(phase) = est.next_phase() {
        let outputs = buffers.for_phase(&phase);
        for out in outputs.iter_mut() {
            est.map(ctx, &phase, out);
            counters += out.counters;
        }
        if phase.samples {
            samples += phase.items as u64;
        }
        est.reduce(ctx, &phase, outputs, film);
    }
    (counters, samples)
}

/// Run setup (if pending) and pass `pass` serially into `film`.
pub fn render_pass<Q: RayQuery + ?Sized, E: Phased<Q> + ?Sized>(
    est: &mut E,
    ctx: &Context<'_, Q>,
    film: &mut Film,
    buffers: &mut PhaseBuffers<E::Data>,
    pass: u32,
) -> (Counters, u64) {
    est.start_pass(pass);
    run_phases(est, ctx, film, buffers)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cursor_runs_setup_then_queued_passes() {
        let mut c = Cursor::new(2, 3);
        assert_eq!(c.stage(), Some(Stage::Setup(0)));
        c.start_pass(7);
        assert!(!c.advance());
        assert_eq!(c.stage(), Some(Stage::Setup(1)));
        assert!(!c.advance());
        assert_eq!(c.stage(), Some(Stage::Pass(7, 0)));
        assert!(!c.advance());
        assert!(!c.advance());
        assert!(c.advance(), "third phase ends the pass");
        assert_eq!(c.stage(), None);
        c.start_pass(8);
        assert_eq!(c.stage(), Some(Stage::Pass(8, 0)));
        let mut none = Cursor::new(0, 1);
        assert_eq!(none.stage(), None);
        none.start_pass(0);
        assert_eq!(none.stage(), Some(Stage::Pass(0, 0)));
    }

    /// About 256 chunks where the phase is large enough, within 64..=1024 items each.
    #[test]
    fn chunks_are_many_and_bounded() {
        for (items, chunk) in [(0, 64), (1, 64), (4096, 64), (65_536, 256), (76_800, 512), (2_073_600, 1024), (u32::MAX, 1024)] {
            assert_eq!(chunk_for(items), chunk, "{items} items");
        }
    }

    #[test]
    fn chunks_cover_the_range_once() {
        let p = Phase { name: "x", id: 0, pass: None, items: 10, chunk: 4, samples: false };
        assert_eq!(p.chunk_count(), 3);
        assert_eq!([p.chunk_range(0), p.chunk_range(1), p.chunk_range(2)], [0..4, 4..8, 8..10]);
        let empty = Phase { items: 0, ..p };
        assert_eq!(empty.chunk_count(), 0);
    }
}
