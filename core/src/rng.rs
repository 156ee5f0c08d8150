//! Counter-based random numbers: every value is a pure function of
//! (seed, stream, index, sample, pass, dimension).
//!
//! No generator state crosses threads or samples, so an image never depends on the
//! thread count or on scheduling, and any single sample can be replayed from its key.
//! The hash is a 64-bit finaliser chain (Stafford's "Mix13" variant of SplitMix64,
//! which passes PractRand/BigCrush as a counter hash); each 64-bit output yields one
//! 24-bit-mantissa float, so every f32 lies in [0, 1) exactly.

use crate::math::Vec2;

/// Which family of random streams a sample belongs to. Keeps camera paths, light paths
/// and preprocessing passes with equal indices from sharing numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum Stream {
    /// Camera sub-paths; `index` is the pixel (y * width + x).
    Camera = 0,
    /// Light sub-paths; `index` is the light-path number within the pass.
    Light = 1,
    /// Preprocessing (training data, caches); `index` is free for the caller.
    Preprocess = 2,
    /// Tests and tools.
    Aux = 3,
}

/// The key from which a sample's random numbers are derived.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SampleKey {
    pub seed: u64,
    pub stream: Stream,
    pub index: u32,
    pub sample: u32,
    pub pass: u32,
}

#[inline]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// The 64 bits of dimension `d` of the stream whose hashed key is `base`.
#[inline(always)]
fn bits_at(base: u64, d: u32) -> u64 {
    mix64(base.wrapping_add((d as u64 + 1).wrapping_mul(GOLDEN)))
}

#[inline(always)]
fn to_f32(bits: u64) -> f32 {
    (bits >> 40) as f32 * (1.0 / 16_777_216.0)
}

/// [`SampleStream::next_f32`] at dimension `d` of the stream whose [`SampleStream::base`]
/// is `base`, without a stream: the same bits, for code that draws over lanes of paths.
#[inline(always)]
pub(crate) fn uniform_at(base: u64, d: u32) -> f32 {
    to_f32(bits_at(base, d))
}

/// A sequence of random numbers for one key, advancing a dimension counter.
#[derive(Clone, Debug)]
pub struct SampleStream {
    base: u64,
    dimension: u32,
}

impl SampleStream {
    /// Stream for `key`, starting at dimension 0.
    #[inline]
    pub fn new(key: SampleKey) -> Self {
        let mut h = mix64(key.seed ^ GOLDEN);
        h = mix64(h ^ ((key.stream as u64) << 32 | key.pass as u64));
        h = mix64(h ^ ((key.index as u64) << 32 | key.sample as u64));
        Self { base: h, dimension: 0 }
    }

    /// Convenience constructor.
    #[inline]
    pub fn for_sample(seed: u64, stream: Stream, index: u32, sample: u32, pass: u32) -> Self {
        Self::new(SampleKey { seed, stream, index, sample, pass })
    }

    /// The dimension the next call will use.
    #[inline]
    pub fn dimension(&self) -> u32 {
        self.dimension
    }

    /// Jump to an absolute dimension (so optional branches need not shift later ones).
    #[inline]
    pub fn set_dimension(&mut self, dimension: u32) {
        self.dimension = dimension;
    }

    /// Raw 64 random bits for the current dimension; advances it.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        let d = self.dimension;
        self.dimension = self.dimension.wrapping_add(1);
        bits_at(self.base, d)
    }

    /// Uniform float in [0, 1).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        to_f32(self.next_u64())
    }

    /// The stream's key hashed: with a dimension, all its numbers ([`uniform_at`]).
    #[inline]
    pub(crate) fn base(&self) -> u64 {
        self.base
    }

    /// Uniform double in [0, 1).
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / 9_007_199_254_740_992.0)
    }

    /// Two uniform floats in [0, 1)².
    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let a = self.next_f32();
        let b = self.next_f32();
        Vec2::new(a, b)
    }

    /// Uniform integer in [0, n) by Lemire's multiply-shift (bias < 2⁻³²·n, no division).
    #[inline]
    pub fn next_below(&mut self, n: u32) -> u32 {
        (((self.next_u64() >> 32) * n as u64) >> 32) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_key_same_numbers_and_distinct_keys_differ() {
        let mut a = SampleStream::for_sample(7, Stream::Camera, 3, 4, 5);
        let mut b = SampleStream::for_sample(7, Stream::Camera, 3, 4, 5);
        let mut c = SampleStream::for_sample(7, Stream::Light, 3, 4, 5);
        for _ in 0..16 {
            let (x, y, z) = (a.next_f32(), b.next_f32(), c.next_f32());
            assert_eq!(x, y);
            assert_ne!(x, z);
            assert!((0.0..1.0).contains(&x));
        }
    }

    #[test]
    fn mean_and_variance_of_uniforms() {
        let n = 200_000;
        let (mut s, mut s2) = (0.0f64, 0.0f64);
        for i in 0..n {
            let x = SampleStream::for_sample(1, Stream::Aux, i, 0, 0).next_f64();
            s += x;
            s2 += x * x;
        }
        let mean = s / n as f64;
        let var = s2 / n as f64 - mean * mean;
        // sd of the mean = sqrt(1/12/n) ≈ 6.5e-4; 5 sd.
        assert!((mean - 0.5).abs() < 3.3e-3, "mean {mean}");
        assert!((var - 1.0 / 12.0).abs() < 2e-3, "var {var}");
    }
}
