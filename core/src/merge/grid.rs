//! A hash grid over points (Teschner et al. 2003's spatial hashing, built by counting
//! sort as in SmallVCM's `HashGrid`).
//!
//! Cells are cubes of side 2r, so the ball of radius r around a query point overlaps at
//! most 2 × 2 × 2 cells (3 per axis when rounding puts both ends just across a boundary). Cells hash into a table of 2^k buckets (k chosen from the point
//! count); a bucket may hold points of several cells, and the distance test sorts them
//! out. Two query cells can land in the same bucket: each bucket is visited once per
//! query, so no point is reported twice. Points far outside the points' bounding box are
//! still queried correctly (no early rejection, which SmallVCM does and which is slightly
//! biased for queries whose ball reaches into the box from outside).
//!
//! Storage is reused: [`HashGrid::build`] clears and refills its vectors, so after the
//! first pass of a render no allocation happens unless the point count grows.

use super::slots::{Slots, cell_of};
use crate::math::Vec3;

/// A hash grid over the points given to [`HashGrid::build`].
#[derive(Clone, Debug, Default)]
pub struct HashGrid {
    radius: f32,
    inv_cell: f32,
    /// The points in bucket order (copied, so a query reads positions contiguously).
    slots: Slots,
    mask: u32,
}

impl HashGrid {
    /// An empty grid (no points; every query finds nothing).
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

    /// Bytes held (capacity, not length).
    pub fn size_bytes(&self) -> usize {
        self.slots.size_bytes()
    }

    /// Rebuild over `points` for queries of radius `radius` (> 0 and finite; otherwise
    /// the grid is left empty). Point i is reported to queries as index i; a point that
    /// is not finite is left out (a host's way to keep an item from every query).
    pub fn build(&mut self, points: impl ExactSizeIterator<Item = Vec3> + Clone, radius: f32) {
        self.slots.clear();
        self.radius = radius;
        let n = points.len();
        if !(radius > 0.0 && radius.is_finite()) || n == 0 || n > u32::MAX as usize / 2 {
            self.mask = 0;
            self.inv_cell = 0.0;
            return;
        }
        self.inv_cell = 0.5 / radius;
        let buckets = n.next_power_of_two().max(16);
        self.mask = buckets as u32 - 1;
        let (inv_cell, mask) = (self.inv_cell, self.mask);
        self.slots.fill(points, buckets, |p| bucket(cell_of(p, inv_cell), mask));
    }

    /// The original index of the point in each slot (bucket order): hosts of per-point
    /// data reorder it by this to read it contiguously in [`Self::query_slots`].
    pub fn order(&self) -> &[u32] {
        &self.slots.indices
    }

    /// Each input point's slot (`u32::MAX` for a point left out): the inverse of
    /// [`Self::order`]. A host building per-point data in slot order reads its inputs in
    /// their own order with it and writes each result to its slot: on spot_mirror's
    /// photons, reading the light vertices in slot order (scattered over a pass's
    /// 100-200 MiB of light paths) made that loop wait on memory for each photon.
    pub fn slot_of(&self) -> &[u32] {
        &self.slots.slot_of
    }

    /// Call `visit(i)` for every point i within distance `radius()` of `p`, once each.
    pub fn query(&self, p: Vec3, mut visit: impl FnMut(u32)) {
        self.query_slots(p, |k| visit(self.slots.indices[k as usize]));
    }

    /// [`Self::query`] reporting slots (positions in bucket order, see [`Self::order`]).
    pub fn query_slots(&self, p: Vec3, mut visit: impl FnMut(u32)) {
        if self.slots.indices.is_empty() || !p.is_finite() {
            return;
        }
        let r = self.radius;
        let r2 = r * r;
        let lo = cell_of(p - Vec3::splat(r), self.inv_cell);
        let hi = cell_of(p + Vec3::splat(r), self.inv_cell);
        // Two cells per axis in exact arithmetic; three when rounding puts p ± r just
        // across two cell boundaries.
        let mut seen = [u32::MAX; 27];
        let mut n_seen = 0;
        for x in lo[0]..=hi[0].min(lo[0].saturating_add(2)) {
            for y in lo[1]..=hi[1].min(lo[1].saturating_add(2)) {
                for z in lo[2]..=hi[2].min(lo[2].saturating_add(2)) {
                    let b = bucket([x, y, z], self.mask);
                    if seen[..n_seen].contains(&b) {
                        continue;
                    }
                    seen[n_seen] = b;
                    n_seen += 1;
                    self.slots.scan(self.slots.buckets(b, b), p, r2, &mut visit);
                }
            }
        }
    }
}

/// Cell `c`'s bucket in a table of `mask` + 1.
#[inline]
fn bucket(c: [i64; 3], mask: u32) -> u32 {
    let h = (c[0] as u64).wrapping_mul(73_856_093) ^ (c[1] as u64).wrapping_mul(19_349_663) ^ (c[2] as u64).wrapping_mul(83_492_791);
    // Fold the high bits in: the multipliers leave the low bits of nearby cells related.
    ((h ^ (h >> 29) ^ (h >> 47)) as u32) & mask
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;
    use alloc::vec::Vec;

    fn lcg(state: &mut u64) -> f32 {
        *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*state >> 40) as f32) / (1u64 << 24) as f32
    }

    /// Every query finds exactly the points a brute-force scan finds, each once, for
    /// clustered and spread points and queries inside and far outside the points' box.
    /// Seen failing with the bucket de-duplication removed (points reported twice) and
    /// with cells of side r/2 instead of 2r (points missed).
    #[test]
    fn queries_match_brute_force() {
        let mut s = 7u64;
        for &(n, r, spread) in &[(1usize, 0.1f32, 1.0f32), (500, 0.05, 1.0), (3000, 0.2, 0.5), (2000, 1e-3, 1e-2), (100, 10.0, 1.0)] {
            let pts: Vec<Vec3> = (0..n).map(|_| Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * spread - Vec3::splat(0.3)).collect();
            let mut g = HashGrid::new();
            g.build(pts.iter().copied(), r);
            assert_eq!(g.len(), n);
            // `slot_of` inverts `order` (seen failing with the slot left at the bucket).
            for (k, &i) in g.order().iter().enumerate() {
                assert_eq!(g.slot_of()[i as usize], k as u32);
            }
            for q in 0..400 {
                let scale = if q % 4 == 0 { 3.0 } else { 1.0 };
                let p = (Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * spread - Vec3::splat(0.3)) * scale;
                let mut found = vec![0u32; n];
                g.query(p, |i| found[i as usize] += 1);
                for (i, &c) in found.iter().enumerate() {
                    let inside = (pts[i] - p).length_squared() <= r * r;
                    assert_eq!(c, inside as u32, "point {i} of {n}, r = {r}");
                }
            }
        }
    }

    #[test]
    fn bad_radius_or_no_points_is_empty_and_keeps_capacity() {
        let mut g = HashGrid::new();
        g.build([Vec3::ZERO].into_iter(), f32::NAN);
        assert!(g.is_empty());
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

    /// Non-finite points are left out and the others keep their indices.
    #[test]
    fn non_finite_points_are_left_out() {
        let mut g = HashGrid::new();
        g.build([Vec3::ZERO, Vec3::NAN, Vec3::new(0.01, 0.0, 0.0), Vec3::splat(f32::INFINITY)].into_iter(), 0.5);
        assert_eq!(g.len(), 2);
        assert_eq!((g.slot_of()[1], g.slot_of()[3]), (u32::MAX, u32::MAX));
        let mut found = Vec::new();
        g.query(Vec3::ZERO, |i| found.push(i));
        found.sort();
        assert_eq!(found, [0, 2]);
    }
}
