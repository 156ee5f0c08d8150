//! A pass committed on the host's threads, in two parallel steps with nothing between
//! them but summing tallies.
//!
//! 1. **Sort.** The pass's splats are cut into contiguous segments; each segment's task
//!    checks its splats ([`super::admit`]) and lists each admitted one under every band of
//!    rows its filter footprint reaches, in staging order.
//! 2. **Rows.** Each band's task adds the camera samples of its rows (under a wide filter:
//!    the staged samples of its rows and of the rows around them that reach its rows,
//!    [`super::spread`]), then the splats listed under it by segment 0, 1, … in turn: the
//!    staging order again.
//!
//! Every pixel receives exactly the additions of the sequential commit, and the sums are
//! fixed-point integers (order-free anyway), so the film is the same bit for bit
//! whatever the runner does, and the tallies are integer sums. Until 2026-11-27 the sort
//! and the camera samples ran on the calling thread: measured on 16 cores, that serial
//! part held light tracing of the Cornell box to 7× (docs/performance.md, "Thread
//! scaling on 16 cores").

use alloc::vec::Vec;
use core::ops::Range;

use super::spread::{WeightedSum, spread_camera_rows};
use super::{Film, Tallies, add, admit, rows_reached, splat_rows};
use crate::spectrum::Rgb;
use crate::transport::Splat;

/// A worker's share of committing a pass: sorting a segment of its splats by band, or
/// adding its camera samples and splats to a band of rows (see [`ParallelBands`]).
#[derive(Debug)]
pub struct Band<'a>(Share<'a>);

#[derive(Debug)]
enum Share<'a> {
    /// List the admitted splats among `splats` (indices into the pass's splats) under
    /// every band they reach: `lists[b]` for band `b`.
    Sort { splats: Range<usize>, lists: &'a mut [Vec<u32>], tallies: Tallies },
    /// Band `band`: rows `rows`, their sums and where their camera samples go.
    Rows { band: usize, rows: Range<u32>, sums: &'a mut [[u128; 3]], camera: CameraRows<'a>, tallies: Tallies },
}

/// A band's camera samples: its own staged ones (the box: each to its pixel, then
/// cleared), or its rows' weighted sums (a wide filter: every staged sample that reaches
/// the rows, read from the whole image's staging).
#[derive(Debug)]
enum CameraRows<'a> {
    Own(&'a mut [Rgb]),
    Spread(&'a mut [WeightedSum]),
}

/// How a host with threads commits a pass: call `work` once for every band, in any order,
/// on any threads (e.g. rayon's `par_iter_mut`). A commit calls the runner twice (sort,
/// then rows); the bands of one call share nothing mutable, so the sums and tallies are
/// the sequential commit's, bit for bit, whatever the runner does.
pub type ParallelBands = for<'a, 'b, 'c> fn(&'a mut [Band<'b>], &'c (dyn Fn(&mut Band<'_>) + Sync + 'c));

/// Bands of rows a parallel commit cuts the film into (more than threads, for balance:
/// splats crowd into some rows).
const BANDS: u32 = 64;
/// The fewest splats, and the fewest pixels of camera samples, worth cutting for.
pub(super) const PARALLEL_SPLATS: usize = 1 << 14;
pub(super) const PARALLEL_PIXELS: usize = 1 << 14;
/// Splats per sorting task, and the most tasks.
const SORT_SPLATS: usize = 1 << 12;
const SEGMENTS: usize = 64;

/// The sort's lists, segment-major (`segment · bands + band`), kept between passes so
/// that a pass allocates only where a list outgrows its last size. Scratch: never part
/// of a film's contents or comparisons.
#[derive(Clone, Default)]
pub(super) struct Lists(Vec<Vec<u32>>);

impl PartialEq for Lists {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl core::fmt::Debug for Lists {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "Lists({})", self.0.len())
    }
}

impl Film {
    /// Whether a pass of `splats` splats is worth committing through a runner.
    pub(super) fn worth_bands(&self, splats: usize) -> bool {
        self.height >= 2 && self.width >= 1 && (splats >= PARALLEL_SPLATS || (self.camera_pass.is_some() && self.sum.len() >= PARALLEL_PIXELS))
    }

    /// Commit the staged camera samples and `splats` × `scale` through `run`.
    pub(super) fn commit_in_bands(&mut self, run: ParallelBands, splats: &[Splat], scale: f64) {
        let (width, height, filter) = (self.width, self.height, self.filter);
        let rows_per = height.div_ceil(BANDS.min(height));
        let bands = height.div_ceil(rows_per) as usize;
        let segments = splats.len().div_ceil(SORT_SPLATS).min(SEGMENTS);
        let per_segment = splats.len().div_ceil(segments.max(1));
        if self.lists.0.len() < segments * bands {
            self.lists.0.resize_with(segments * bands, Vec::new);
        }
        let lists = &mut self.lists.0[..segments * bands];

        // 1. Sort.
        let mut sorts: Vec<Band> = lists
            .chunks_mut(bands)
            .enumerate()
            .map(|(k, lists)| {
                lists.iter_mut().for_each(Vec::clear);
                let first = k * per_segment;
                Band(Share::Sort { splats: first..(first + per_segment).min(splats.len()), lists, tallies: Tallies::default() })
            })
            .collect();
        run(&mut sorts, &|task: &mut Band| {
            let Share::Sort { splats: range, lists, tallies } = &mut task.0 else { return };
            for i in range.clone() {
                let s = &splats[i];
                if !admit(tallies, s, width, height) {
                    continue;
                }
                let rows = rows_reached(filter, s, height);
                if rows.is_empty() {
                    continue;
                }
                for list in &mut lists[(rows.start / rows_per) as usize..=((rows.end - 1) / rows_per) as usize] {
                    list.push(i as u32);
                }
            }
        });
        for task in &sorts {
            if let Share::Sort { tallies, .. } = &task.0 {
                self.tallies.add(tallies);
            }
        }
        drop(sorts);

        // 2. Rows.
        let (camera_pass, lists) = (self.camera_pass, &self.lists.0[..segments * bands]);
        let band_len = rows_per as usize * width as usize;
        let spread = !filter.is_box() && !self.weighted.is_empty();
        let (targets, staged): (Vec<CameraRows>, &[Rgb]) = if spread {
            (self.weighted.chunks_mut(band_len).map(CameraRows::Spread).collect(), &self.camera)
        } else {
            (self.camera.chunks_mut(band_len).map(CameraRows::Own).collect(), &[])
        };
        let mut rows: Vec<Band> = self
            .sum
            .chunks_mut(band_len)
            .zip(targets)
            .enumerate()
            .map(|(band, (sums, camera))| {
                let first = band as u32 * rows_per;
                Band(Share::Rows { band, rows: first..(first + rows_per).min(height), sums, camera, tallies: Tallies::default() })
            })
            .collect();
        run(&mut rows, &|task: &mut Band| {
            let Share::Rows { band, rows, sums, camera, tallies } = &mut task.0 else { return };
            match (camera_pass, camera) {
                (None, _) => {}
                (Some(_), CameraRows::Own(camera)) => {
                    for (acc, v) in sums.iter_mut().zip(camera.iter_mut()) {
                        commit_camera_sample(tallies, acc, v);
                    }
                }
                (Some(at), CameraRows::Spread(weighted)) => spread_camera_rows(filter, at, width, height, staged, weighted, rows.clone(), tallies),
            }
            for segment in lists.chunks(bands) {
                for &i in &segment[*band] {
                    tallies.saturated += splat_rows(filter, width, height, sums, rows.clone(), &splats[i as usize], scale);
                }
            }
        });
        for task in &rows {
            if let Share::Rows { tallies, .. } = &task.0 {
                self.tallies.add(tallies);
            }
        }
        drop(rows);
        if spread && camera_pass.is_some() {
            self.camera.fill(Rgb::ZERO);
        }
    }
}

/// Add staged camera sample `v` to its pixel's sums `acc` (or tally it discarded), and
/// clear it for the next pass.
#[inline]
pub(super) fn commit_camera_sample(tallies: &mut Tallies, acc: &mut [u128; 3], v: &mut Rgb) {
    if v.is_valid_radiance() {
        tallies.saturated += add(acc, *v, 1.0);
    } else {
        tallies.discarded += 1;
    }
    *v = Rgb::ZERO;
}
