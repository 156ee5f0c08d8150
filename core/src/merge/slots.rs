//! What both grids ([`super::HashGrid`], [`super::CellGrid`]) keep of their points and how
//! a query tests them: the points in bucket order ("slots", filled by counting sort into
//! storage reused across builds), their positions as structures of arrays, and the scan
//! of a range of slots, [`LANES`] points at a time.

use alloc::vec::Vec;
use core::ops::Range;

use crate::math::Vec3;

/// Points a scan tests at a time.
const LANES: usize = 8;

/// Points in bucket order.
#[derive(Clone, Debug, Default)]
pub(super) struct Slots {
    /// Bucket b's points are at slots `starts[b] .. starts[b + 1]`.
    starts: Vec<u32>,
    /// The input index of the point in each slot.
    pub indices: Vec<u32>,
    /// Positions by slot.
    xs: Vec<f32>,
    ys: Vec<f32>,
    zs: Vec<f32>,
    /// Each input point's bucket while filling, then its slot (`u32::MAX`: left out).
    pub slot_of: Vec<u32>,
}

impl Slots {
    /// Forget every point, keeping the storage.
    pub fn clear(&mut self) {
        self.starts.clear();
        self.indices.clear();
        self.xs.clear();
        self.ys.clear();
        self.zs.clear();
        self.slot_of.clear();
    }

    /// Bytes held (capacity).
    pub fn size_bytes(&self) -> usize {
        (self.starts.capacity() + self.indices.capacity() + self.slot_of.capacity() + self.xs.capacity() + self.ys.capacity() + self.zs.capacity()) * 4
    }

    /// Counting sort of `points` into `buckets` buckets by `bucket_of` (below `buckets`):
    /// counts, exclusive prefix sums, then each point at its bucket's cursor; the cursors
    /// end at the bucket ends, shifted back into the starts. Points that are not finite
    /// are left out. Within a bucket the input order is kept.
    pub fn fill(&mut self, points: impl ExactSizeIterator<Item = Vec3> + Clone, buckets: usize, bucket_of: impl Fn(Vec3) -> u32) {
        self.clear();
        self.starts.resize(buckets + 1, 0);
        let mut kept = 0usize;
        for p in points.clone() {
            if !p.is_finite() {
                self.slot_of.push(u32::MAX);
                continue;
            }
            let b = bucket_of(p);
            self.slot_of.push(b);
            self.starts[b as usize] += 1;
            kept += 1;
        }
        let mut sum = 0u32;
        for b in 0..buckets {
            let count = self.starts[b];
            self.starts[b] = sum;
            sum += count;
        }
        self.starts[buckets] = sum;
        self.indices.resize(kept, 0);
        self.xs.resize(kept, 0.0);
        self.ys.resize(kept, 0.0);
        self.zs.resize(kept, 0.0);
        for (i, p) in points.enumerate() {
            if self.slot_of[i] == u32::MAX {
                continue;
            }
            let b = self.slot_of[i] as usize;
            let k = self.starts[b] as usize;
            self.indices[k] = i as u32;
            (self.xs[k], self.ys[k], self.zs[k]) = (p.x, p.y, p.z);
            self.slot_of[i] = k as u32;
            self.starts[b] += 1;
        }
        for b in (1..=buckets).rev() {
            self.starts[b] = self.starts[b - 1];
        }
        self.starts[0] = 0;
    }

    /// [`super::CellGrid::relabel_in_order`].
    pub fn relabel_in_order(&mut self, offset: usize, total: usize) {
        let n = self.indices.len();
        for (k, i) in self.indices.iter_mut().enumerate() {
            *i = (offset + k) as u32;
        }
        self.slot_of.clear();
        self.slot_of.resize(total, u32::MAX);
        for (k, s) in self.slot_of[offset..offset + n].iter_mut().enumerate() {
            *s = k as u32;
        }
    }

    /// The coordinates by slot.
    pub fn positions(&self) -> (&[f32], &[f32], &[f32]) {
        (&self.xs, &self.ys, &self.zs)
    }

    /// The slots of buckets `first ..= last`.
    #[inline]
    pub fn buckets(&self, first: u32, last: u32) -> Range<usize> {
        self.starts[first as usize] as usize..self.starts[last as usize + 1] as usize
    }

    /// Call `visit(k)` for each slot k in `slots` whose point lies within √`r2` of `p`,
    /// in slot order. [`LANES`] points are tested at a time, each by the scalar test
    /// (q − p)·(q − p) ≤ r² summed in one order, so the same slots are reported as one
    /// at a time: the compiler turns the fixed-width loop into vector compares and a
    /// mask, whatever instruction set the core is built for. On the filters, where a
    /// query scanned about six points for each one in its ball, the scalar loop was the
    /// largest single cost of a pass.
    #[inline]
    pub fn scan(&self, slots: Range<usize>, p: Vec3, r2: f32, visit: &mut impl FnMut(u32)) {
        let (xs, ys, zs) = (&self.xs[slots.clone()], &self.ys[slots.clone()], &self.zs[slots.clone()]);
        let n = xs.len();
        let mut j = 0;
        while j < n {
            let mut mask = if j + LANES <= n {
                inside_mask(block(&xs[j..]), block(&ys[j..]), block(&zs[j..]), p, r2)
            } else {
                // The last, partial block, padded with points that are never inside
                // (NaN compares false).
                let pad = |v: &[f32]| core::array::from_fn(|l| v.get(j + l).copied().unwrap_or(f32::NAN));
                inside_mask(&pad(xs), &pad(ys), &pad(zs), p, r2)
            };
            // One call site for `visit`, so that the compiler inlines it.
            while mask != 0 {
                visit((slots.start + j) as u32 + mask.trailing_zeros());
                mask &= mask - 1;
            }
            j += LANES;
        }
    }
}

/// The first [`LANES`] values of `v` (which has at least that many).
#[inline(always)]
fn block(v: &[f32]) -> &[f32; LANES] {
    v[..LANES].try_into().expect("a full block")
}

/// Bit l set where point l of the block lies within √`r2` of `p`: (q − p)·(q − p) ≤ r²,
/// summed in one order on every lane.
#[inline(always)]
fn inside_mask(x: &[f32; LANES], y: &[f32; LANES], z: &[f32; LANES], p: Vec3, r2: f32) -> u32 {
    let mut mask = 0u32;
    for l in 0..LANES {
        let (dx, dy, dz) = (x[l] - p.x, y[l] - p.y, z[l] - p.z);
        mask |= ((dx * dx + dy * dy + dz * dz <= r2) as u32) << l;
    }
    mask
}

/// The cell of `p` for cells of side 1 / `inv_cell`. Saturating float-to-int casts:
/// far-away points share the outermost cells.
#[inline]
pub(super) fn cell_of(p: Vec3, inv_cell: f32) -> [i64; 3] {
    let c = p * inv_cell;
    [crate::math::floor(c.x) as i64, crate::math::floor(c.y) as i64, crate::math::floor(c.z) as i64]
}
