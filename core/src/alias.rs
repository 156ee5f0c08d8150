//! Discrete distributions by Walker–Vose alias tables: O(n) build (allocates, at setup),
//! O(1) sampling with one uniform number and no allocation.

use alloc::vec::Vec;

/// One bin: the probability of keeping it and the index to take otherwise, with the
/// probabilities of both outcomes, so that a draw reads one bin (one cache line) and not
/// a second array: SPCBPT draws from tables too large for the cache several times per
/// camera vertex.
#[derive(Clone, Copy, Debug, Default)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
struct Bin {
    keep: f32,
    alias: u32,
    /// Probability of this bin's own outcome.
    pmf: f32,
    /// Probability of outcome `alias`.
    alias_pmf: f32,
}

/// A discrete distribution over `0..n` proportional to non-negative weights.
#[derive(Clone, Debug, Default)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct AliasTable {
    bins: Vec<Bin>,
    total: f64,
}

/// Result of [`AliasTable::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiscreteSample {
    pub index: usize,
    /// Probability of `index` (same value [`AliasTable::pmf`] returns).
    pub pmf: f32,
    /// The uniform number re-stretched to [0, 1) within the chosen bin, reusable.
    pub u_remapped: f32,
}

impl AliasTable {
    /// Build from weights. Negative and non-finite weights count as zero. Returns `None`
    /// when no weight is positive (there is nothing to sample).
    pub fn new(weights: &[f32]) -> Option<Self> {
        let n = weights.len();
        if n == 0 || n > u32::MAX as usize {
            return None;
        }
        let clean = |w: f32| if w.is_finite() && w > 0.0 { w as f64 } else { 0.0 };
        let total: f64 = weights.iter().map(|&w| clean(w)).sum();
        if !(total > 0.0) || !total.is_finite() {
            return None;
        }
        let pmf: Vec<f32> = weights.iter().map(|&w| (clean(w) / total) as f32).collect();
        // Scaled probabilities n·p; split into under- and over-full work lists.
        let mut scaled: Vec<f64> = weights.iter().map(|&w| clean(w) / total * n as f64).collect();
        let mut bins = alloc::vec![Bin::default(); n];
        let mut small: Vec<u32> = Vec::with_capacity(n);
        let mut large: Vec<u32> = Vec::with_capacity(n);
        for (i, &s) in scaled.iter().enumerate() {
            if s < 1.0 { small.push(i as u32) } else { large.push(i as u32) }
        }
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            bins[s as usize] = Bin { keep: scaled[s as usize] as f32, alias: l, ..Bin::default() };
            scaled[l as usize] -= 1.0 - scaled[s as usize];
            if scaled[l as usize] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // Leftovers are full bins up to rounding.
        for i in small.into_iter().chain(large) {
            bins[i as usize] = Bin { keep: 1.0, alias: i, ..Bin::default() };
        }
        for (i, bin) in bins.iter_mut().enumerate() {
            bin.pmf = pmf[i];
            bin.alias_pmf = pmf[bin.alias as usize];
        }
        Some(Self { bins, total })
    }

    /// Number of outcomes.
    #[inline]
    pub fn len(&self) -> usize {
        self.bins.len()
    }
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.bins.is_empty()
    }
    /// Heap bytes held.
    #[inline]
    pub fn size_bytes(&self) -> usize {
        self.bins.capacity() * core::mem::size_of::<Bin>()
    }
    /// Sum of the (clean) weights the table was built from.
    #[inline]
    pub fn total_weight(&self) -> f64 {
        self.total
    }

    /// Probability of outcome `i` (0 outside the range).
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.bins.get(i).map_or(0.0, |b| b.pmf)
    }

    /// Draw an outcome with one uniform number `u` in [0, 1).
    #[inline]
    pub fn sample(&self, u: f32) -> DiscreteSample {
        let n = self.bins.len();
        let x = u * n as f32;
        let i = (x as usize).min(n - 1);
        let frac = (x - i as f32).clamp(0.0, 1.0);
        let bin = self.bins[i];
        let (index, pmf, u_remapped) = if frac < bin.keep {
            (i, bin.pmf, if bin.keep > 0.0 { frac / bin.keep } else { 0.0 })
        } else {
            (bin.alias as usize, bin.alias_pmf, ((frac - bin.keep) / (1.0 - bin.keep)).clamp(0.0, 1.0))
        };
        DiscreteSample { index, pmf, u_remapped: u_remapped.min(1.0 - f32::EPSILON * 0.5) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frequencies_match_weights() {
        let w = [1.0, 0.0, 3.0, 0.5, 5.5, f32::NAN, -2.0];
        let t = AliasTable::new(&w).unwrap();
        let n = 400_000;
        let mut counts = [0usize; 7];
        for k in 0..n {
            let u = (k as f32 + 0.5) / n as f32;
            let d = t.sample(u);
            // The probability carried in the bin is the outcome's (seen to fail when a
            // bin kept its own probability for its alias: u = 0.10000125).
            assert_eq!(d.pmf.to_bits(), t.pmf(d.index).to_bits(), "u = {u}");
            counts[d.index] += 1;
        }
        for i in 0..7 {
            let expected = t.pmf(i) as f64;
            let got = counts[i] as f64 / n as f64;
            // A stratified sweep is exact up to the bin-boundary quantisation.
            assert!((expected - got).abs() < 1e-4, "bin {i}: {expected} vs {got}");
        }
        assert_eq!(counts[1] + counts[5] + counts[6], 0);
    }

    #[test]
    fn no_positive_weight_is_none() {
        assert!(AliasTable::new(&[]).is_none());
        assert!(AliasTable::new(&[0.0, -1.0, f32::NAN]).is_none());
    }
}
