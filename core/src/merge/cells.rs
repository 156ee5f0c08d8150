//! A grid for fixed-radius neighbour queries whose cells are as wide as the query radius,
//! laid out so that a query reads a few contiguous runs of points.
//!
//! [`super::HashGrid`]'s cells are twice the query radius R, so a query scans the 2 × 2 × 2
//! cells around its ball: on points spread over surfaces, about six points for each one
//! in the ball. The segment filters query every node's kernel several times per pass, and
//! that scan was the largest cost of a pass. Here cells have side R: a query's box
//! [p − R, p + R] touches 3 cells per axis (4 where rounding puts both ends just across a
//! boundary), 3 R across instead of 4 R, so on a surface it scans about 3² / 4² of what
//! the hash grid scans. (Cells of side R/2 scan less again, but their 5 × 5 runs per query
//! cost more than they saved: a bidirectional filtering pass on the Cornell box took 1.14×
//! the hash grid's time, against 0.79× with side R.)
//!
//! More cells per query would mean more lookups, so cells hash by rows: cell (x, y, z)
//! goes to bucket (h(y, z) + x) mod 2^k. The cells of one row along x are consecutive
//! buckets, and points are stored in bucket order, so the up to 4 × 4 rows a query
//! touches are as many contiguous ranges of slots. Two rows may share buckets (a hash
//! collision, or a range that wraps around the table): the ranges are sorted and merged
//! before the scan, so each slot is scanned once and a point is never reported twice.
//! A bucket may hold points of cells outside the query box; the distance test rejects
//! them, so collisions cost time, never correctness.
//!
//! Order: a query reports points in slot order (bucket order, then input order within a
//! bucket), whatever the thread count. Storage is reused across builds.

use super::slots::{Slots, cell_of};
use crate::math::Vec3;

/// Cells per query radius along each axis.
const CELLS_PER_RADIUS: f32 = 1.0;

/// Most row ranges a query can touch: 4 × 4 rows, each split in two where it wraps.
const MAX_RANGES: usize = 32;

/// A grid over the points given to [`CellGrid::build`], for queries of one radius.
#[derive(Clone, Debug, Default)]
pub struct CellGrid {
    radius: f32,
    inv_cell: f32,
    /// The points in bucket order.
    slots: Slots,
    mask: u32,
}

impl CellGrid {
    /// An empty grid (every query finds nothing).
    pub fn new() -> Self {
        Self::default()
    }

    /// The query radius the grid was built for.
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// Number of points held.
    pub fn len(&self) -> usize {
        self.slots.indices.len()
    }

    /// Does it hold no point?
    pub fn is_empty(&self) -> bool {
        self.slots.indices.is_empty()
    }

    /// Bytes held (capacity).
    pub fn size_bytes(&self) -> usize {
        self.slots.size_bytes()
    }

    /// Rebuild over `points` for queries of radius `radius` (> 0 and finite; otherwise the
    /// grid is left empty). Point i is reported as index i; a point that is not finite is
    /// left out.
    pub fn build(&mut self, points: impl ExactSizeIterator<Item = Vec3> + Clone, radius: f32) {
        self.slots.clear();
        self.radius = radius;
        let n = points.len();
        if !(radius > 0.0 && radius.is_finite()) || n == 0 || n > u32::MAX as usize / 4 {
            self.mask = 0;
            self.inv_cell = 0.0;
            return;
        }
        self.inv_cell = CELLS_PER_RADIUS / radius;
        // About two buckets per point: rows of a few points each hash apart.
        let buckets = (2 * n).next_power_of_two().max(64);
        self.mask = buckets as u32 - 1;
        let (inv_cell, mask) = (self.inv_cell, self.mask);
        self.slots.fill(points, buckets, |p| bucket(cell_of(p, inv_cell), mask));
    }

    /// The input index of the point in each slot: hosts reorder their per-point data by
    /// it so that queries read it contiguously.
    pub fn order(&self) -> &[u32] {
        &self.slots.indices
    }

    /// Each input point's slot (`u32::MAX` for a point left out): the inverse of
    /// [`Self::order`].
    pub fn slot_of(&self) -> &[u32] {
        &self.slots.slot_of
    }

    /// Call `visit(i)` for every point i within distance `radius()` of `p`, once each, in
    /// slot order.
    pub fn query(&self, p: Vec3, mut visit: impl FnMut(u32)) {
        let r2 = self.radius * self.radius;
        let mut report = |k: u32| visit(self.slots.indices[k as usize]);
        self.query_ranges(p, |slots| self.slots.scan(slots, p, r2, &mut report));
    }

    /// Call `visit(slots)` for each run of consecutive slots a query at `p` scans, in slot
    /// order, each slot once: every point within `radius()` of `p` lies in one of them
    /// (with others, which the caller tests; [`Self::query`] keeps those within the
    /// radius). For callers that test the points of a run in lanes of their own
    /// ([`Self::positions`], [`Self::order`]).
    pub fn query_ranges(&self, p: Vec3, mut visit: impl FnMut(core::ops::Range<usize>)) {
        if self.slots.indices.is_empty() || !p.is_finite() {
            return;
        }
        let r = self.radius;
        let lo = cell_of(p - Vec3::splat(r), self.inv_cell);
        let hi = cell_of(p + Vec3::splat(r), self.inv_cell);
        // At most 3 cells per axis in exact arithmetic, 4 where rounding puts p ± R just
        // across two boundaries (the cap only matters for saturated coordinates).
        let last = |l: i64, h: i64| h.min(l.saturating_add(3));
        let (x0, x1) = (lo[0], last(lo[0], hi[0]));
        let mut ranges = [(0u32, 0u32); MAX_RANGES];
        let mut n = 0;
        for z in lo[2]..=last(lo[2], hi[2]) {
            for y in lo[1]..=last(lo[1], hi[1]) {
                let first = bucket([x0, y, z], self.mask);
                let count = (x1 - x0) as u32 + 1;
                // Buckets first ..= first + count − 1, modulo the table.
                let end = first + count - 1;
                if end <= self.mask {
                    ranges[n] = (first, end);
                    n += 1;
                } else {
                    ranges[n] = (first, self.mask);
                    ranges[n + 1] = (0, end - self.mask - 1);
                    n += 2;
                }
            }
        }
        let ranges = &mut ranges[..n];
        // Insertion sort by first bucket (a few dozen ranges), then merge overlaps so that
        // every bucket is scanned once.
        for i in 1..ranges.len() {
            let mut j = i;
            while j > 0 && ranges[j - 1].0 > ranges[j].0 {
                ranges.swap(j - 1, j);
                j -= 1;
            }
        }
        let mut current = ranges[0];
        for &(a, b) in &ranges[1..] {
            if a <= current.1.saturating_add(1) {
                current.1 = current.1.max(b);
            } else {
                visit(self.slots.buckets(current.0, current.1));
                current = (a, b);
            }
        }
        visit(self.slots.buckets(current.0, current.1));
    }

    /// After the caller put its points in [`Self::order`], with this grid's at `offset`
    /// onwards of `total`: report slot k as point `offset + k`, as a rebuild over the
    /// reordered points would (a stable counting sort leaves points already in bucket
    /// order where they are, and the positions by slot do not move).
    pub fn relabel_in_order(&mut self, offset: usize, total: usize) {
        self.slots.relabel_in_order(offset, total);
    }

    /// The points' coordinates by slot (x, y, z), for [`Self::query_ranges`]' callers.
    pub fn positions(&self) -> (&[f32], &[f32], &[f32]) {
        self.slots.positions()
    }
}

/// Row (y, z) hashed, plus x: a row's cells are consecutive buckets of a table of
/// `mask` + 1.
#[inline]
fn bucket(c: [i64; 3], mask: u32) -> u32 {
    let h = (c[1] as u64).wrapping_mul(19_349_663) ^ (c[2] as u64).wrapping_mul(83_492_791);
    let h = (h ^ (h >> 29) ^ (h >> 47)) as u32;
    h.wrapping_add(c[0] as u32) & mask
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;
    use alloc::vec::Vec;

    type Draw = dyn Fn(&mut u64) -> Vec3;

    fn lcg(state: &mut u64) -> f32 {
        *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*state >> 40) as f32) / (1u64 << 24) as f32
    }

    /// Every query finds exactly the points a brute-force scan finds, each once, in slot
    /// order: points in a volume, on a plane, clustered, far apart (rows hashing into
    /// each other in a small table), queries inside and far outside the points, and
    /// points at huge coordinates (saturating cells). Seen failing with overlapping ranges
    /// scanned without the merge (points reported twice), with the range cap at 4 cells
    /// (points missed), and with the wrapped part of a range dropped (points missed).
    #[test]
    fn queries_match_brute_force() {
        let mut s = 11u64;
        let volume = |s: &mut u64| Vec3::new(lcg(s), lcg(s), lcg(s));
        let plane = |s: &mut u64| Vec3::new(lcg(s), 0.25, lcg(s));
        // (points, radius, spread, how a point is drawn)
        let cases: [(usize, f32, f32, &Draw); 9] = [
            (1, 0.1, 1.0, &volume),
            // A 64-bucket table under hundreds of occupied rows: ranges wrap and collide.
            (30, 0.15, 1.0, &volume),
            (20, 0.3, 1.0, &plane),
            (500, 0.05, 1.0, &volume),
            (3000, 0.2, 0.5, &volume),
            (2000, 1e-3, 1e-2, &volume),
            (4000, 0.03, 1.0, &plane),
            (100, 10.0, 1.0, &volume),
            (64, 0.02, 1e4, &volume),
        ];
        for (n, r, spread, draw) in cases {
            let pts: Vec<Vec3> = (0..n).map(|_| draw(&mut s) * spread - Vec3::splat(0.3)).collect();
            let mut g = CellGrid::new();
            g.build(pts.iter().copied(), r);
            assert_eq!(g.len(), n);
            for (k, &i) in g.order().iter().enumerate() {
                assert_eq!(g.slot_of()[i as usize], k as u32);
            }
            for q in 0..400 {
                let scale = if q % 4 == 0 { 3.0 } else { 1.0 };
                let p = if q % 5 == 0 { pts[q % n] } else { (draw(&mut s) * spread - Vec3::splat(0.3)) * scale };
                let mut found = vec![0u32; n];
                let mut last_slot = None;
                g.query(p, |i| {
                    found[i as usize] += 1;
                    let slot = g.slot_of()[i as usize];
                    assert!(last_slot.is_none_or(|l| l < slot), "slot order");
                    last_slot = Some(slot);
                });
                for (i, &c) in found.iter().enumerate() {
                    let inside = (pts[i] - p).length_squared() <= r * r;
                    assert_eq!(c, inside as u32, "point {i} of {n}, r = {r}, query {q}");
                }
            }
        }
        // Huge coordinates: saturated cells, still every point in range found.
        let pts = [Vec3::splat(3e38), Vec3::splat(-3e38), Vec3::new(1e30, 0.0, 0.0), Vec3::ZERO];
        let mut g = CellGrid::new();
        g.build(pts.iter().copied(), 1.0);
        for p in pts {
            let mut found = 0;
            g.query(p, |i| found += (pts[i as usize] == p) as u32);
            assert_eq!(found, 1, "{p:?}");
        }
    }

    /// Seen failing with the wrapped part of a row's range dropped: the 50 points at
    /// (1, 1, 1) sit in a row that wraps around the table.
    #[test]
    fn bad_radius_non_finite_points_and_reuse() {
        let mut g = CellGrid::new();
        g.build([Vec3::ZERO].into_iter(), f32::NAN);
        assert!(g.is_empty());
        g.build([Vec3::ZERO, Vec3::NAN, Vec3::new(0.01, 0.0, 0.0), Vec3::splat(f32::INFINITY)].into_iter(), 0.5);
        assert_eq!(g.len(), 2);
        assert_eq!((g.slot_of()[1], g.slot_of()[3]), (u32::MAX, u32::MAX));
        let mut found = Vec::new();
        g.query(Vec3::ZERO, |i| found.push(i));
        found.sort();
        assert_eq!(found, [0, 2]);
        g.build([Vec3::ZERO; 100].into_iter(), 0.5);
        let bytes = g.size_bytes();
        g.build([Vec3::ONE; 50].into_iter(), 0.5);
        assert_eq!(g.size_bytes(), bytes, "a smaller rebuild reuses the storage");
        let mut hits = 0;
        g.query(Vec3::ONE, |_| hits += 1);
        assert_eq!(hits, 50);
        g.query(Vec3::splat(f32::NAN), |_| hits += 1);
        assert_eq!(hits, 50);
    }
}
