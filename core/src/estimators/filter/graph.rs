//! The propagation of recursive MMIS (eq. 18) over one pass's segments, generic over the
//! float type: the estimator runs it in f32, the brute-force test in f64.
//!
//! Node v is a segment s_v (a camera-path vertex: the segment that reached it). Its row
//! holds what eq. (18) adds to ⟨L(s_v)⟩:
//! - `emission`: L_e(s_v), the radiance its end emits back along it;
//! - `direct`: the terms that end one segment later whatever happens next (light-sampled
//!   segments and continuations that escaped to the environment, reused from every
//!   kernel neighbour);
//! - `(target, coefficient)` pairs: K f_r G / Σ p for each reused continuation segment
//!   s_u' (u a kernel neighbour of v's end), with `target` the node of s_u' (flagged
//!   [`REFLECTED`] where only the target's reflected radiance, L − L_e, is meant).
//!
//! With L_0 = emission and L_d = emission + direct + Σ coefficient · L_{d−1}(target), L_d(v) is
//! eq. (18) over every segment path of at most d further segments: the exponential sum
//! evaluated in d sweeps over the rows, O(d · Σ rows) (the paper's §4.2 and §6.4).

use alloc::vec::Vec;
use core::ops::{Add, Div, Mul};

/// The float types the propagation runs in.
pub trait Real: Copy + Default + PartialOrd + Add<Output = Self> + core::ops::Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> {
    fn from_f32(x: f32) -> Self;
    fn from_f64(x: f64) -> Self;
    fn to_f64(self) -> f64;
    fn zero() -> Self {
        Self::default()
    }
}

impl Real for f32 {
    #[inline]
    fn from_f32(x: f32) -> Self {
        x
    }
    #[inline]
    fn from_f64(x: f64) -> Self {
        x as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self as f64
    }
}

impl Real for f64 {
    #[inline]
    fn from_f32(x: f32) -> Self {
        x as f64
    }
    #[inline]
    fn from_f64(x: f64) -> Self {
        x
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
}

/// An RGB triple in `T`.
pub type Rgb3<T> = [T; 3];

#[inline]
pub fn add3<T: Real>(a: Rgb3<T>, b: Rgb3<T>) -> Rgb3<T> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline]
pub fn mul3<T: Real>(a: Rgb3<T>, b: Rgb3<T>) -> Rgb3<T> {
    [a[0] * b[0], a[1] * b[1], a[2] * b[2]]
}

#[inline]
pub fn scale3<T: Real>(a: Rgb3<T>, s: T) -> Rgb3<T> {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// A radiance in `T`.
#[inline]
pub fn rgb<T: Real>(c: crate::spectrum::Rgb) -> Rgb3<T> {
    [T::from_f32(c.r), T::from_f32(c.g), T::from_f32(c.b)]
}

/// A target flagged with this bit takes the target's L minus its L_e (the reflected
/// part alone, without cancellation against a separate negative term).
pub const REFLECTED: u32 = 1 << 31;

/// One pass's rows (compressed sparse rows over the nodes).
#[derive(Clone, Debug)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct FilterGraph<T> {
    /// L_e per node.
    pub emission: Vec<Rgb3<T>>,
    /// Constant one-segment-later terms per node.
    pub direct: Vec<Rgb3<T>>,
    /// Node v's pairs are `targets[starts[v]..starts[v + 1]]` (one more entry than nodes).
    pub starts: Vec<u32>,
    pub targets: Vec<u32>,
    pub coefficients: Vec<Rgb3<T>>,
}

impl<T> Default for FilterGraph<T> {
    fn default() -> Self {
        Self { emission: Vec::new(), direct: Vec::new(), starts: alloc::vec![0], targets: Vec::new(), coefficients: Vec::new() }
    }
}

impl<T: Real> FilterGraph<T> {
    pub fn new() -> Self {
        Self::default()
    }

    /// Forget every row, keeping the storage.
    pub fn clear(&mut self) {
        self.emission.clear();
        self.direct.clear();
        self.starts.clear();
        self.starts.push(0);
        self.targets.clear();
        self.coefficients.clear();
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.emission.len()
    }

    pub fn is_empty(&self) -> bool {
        self.emission.is_empty()
    }

    /// Append a node's row.
    pub fn push_row(&mut self, emission: Rgb3<T>, direct: Rgb3<T>, pairs: impl IntoIterator<Item = (u32, Rgb3<T>)>) {
        self.emission.push(emission);
        self.direct.push(direct);
        for (t, c) in pairs {
            self.targets.push(t);
            self.coefficients.push(c);
        }
        self.starts.push(self.targets.len() as u32);
    }

    /// Pairs over all rows.
    pub fn pairs(&self) -> usize {
        self.targets.len()
    }

    /// Make room for `rows` more rows and `pairs` more pairs, with headroom where the
    /// storage must grow (the module's `reserve_headroom`).
    pub fn reserve_headroom(&mut self, rows: usize, pairs: usize) {
        reserve_headroom(&mut self.emission, rows);
        reserve_headroom(&mut self.direct, rows);
        reserve_headroom(&mut self.starts, rows);
        reserve_headroom(&mut self.targets, pairs);
        reserve_headroom(&mut self.coefficients, pairs);
    }

    /// Append another graph's rows, its targets shifted by `offset` (chunks built apart).
    pub fn append(&mut self, other: &FilterGraph<T>, offset: u32) {
        let base = self.targets.len() as u32;
        self.emission.extend_from_slice(&other.emission);
        self.direct.extend_from_slice(&other.direct);
        self.starts.extend(other.starts[1..].iter().map(|s| s + base));
        self.targets.extend(other.targets.iter().map(|t| ((t & !REFLECTED) + offset) | (t & REFLECTED)));
        self.coefficients.extend_from_slice(&other.coefficients);
    }

    /// Bytes held (capacity).
    pub fn size_bytes(&self) -> usize {
        let triple = core::mem::size_of::<Rgb3<T>>();
        (self.emission.capacity() + self.direct.capacity() + self.coefficients.capacity()) * triple + (self.starts.capacity() + self.targets.capacity()) * 4
    }

    /// One sweep for nodes `nodes`: `out[i] = L_d(nodes.start + i)` from `prev` = L_{d−1}
    /// over all nodes (`None` for d = 0).
    pub fn sweep(&self, prev: Option<&[Rgb3<T>]>, nodes: core::ops::Range<usize>, out: &mut Vec<Rgb3<T>>) {
        out.clear();
        for v in nodes {
            let mut l = self.emission[v];
            if let Some(prev) = prev {
                l = add3(l, self.direct[v]);
                let (a, b) = (self.starts[v] as usize, self.starts[v + 1] as usize);
                // Slices of the row, zipped: one bounds check per row, not three per pair
                // (the sweeps are a quarter of a pass's instructions).
                for (&t, &c) in self.targets[a..b].iter().zip(&self.coefficients[a..b]) {
                    let x = if t & REFLECTED == 0 {
                        prev[t as usize]
                    } else {
                        let (p, e) = (prev[(t & !REFLECTED) as usize], self.emission[(t & !REFLECTED) as usize]);
                        [p[0] - e[0], p[1] - e[1], p[2] - e[2]]
                    };
                    l = add3(l, mul3(c, x));
                }
            }
            out.push(l);
        }
    }

    /// L_d for every node after `sweeps` sweeps (L_0 = emission), single-threaded.
    pub fn propagate(&self, sweeps: u32) -> Vec<Rgb3<T>> {
        let mut cur = Vec::new();
        self.sweep(None, 0..self.len(), &mut cur);
        let mut next = Vec::new();
        for _ in 0..sweeps {
            self.sweep(Some(&cur), 0..self.len(), &mut next);
            core::mem::swap(&mut cur, &mut next);
        }
        cur
    }
}

/// Make room for `n` more elements. Where the vector must grow it takes a quarter more
/// than it needs, so that the next pass's slightly larger node count fits. `Vec`'s own
/// growth is exact when a vector's first fill reserves its length, as `extend` does.
pub(super) fn reserve_headroom<T>(v: &mut Vec<T>, n: usize) {
    let need = v.len().saturating_add(n);
    if need > v.capacity() {
        v.reserve(need.saturating_add(need / 4) - v.len());
    }
}
