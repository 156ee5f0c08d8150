//! [`Scaled`]: a non-negative f64 with a separate power-of-two exponent, for MMIS
//! denominators that mix densities of wildly different magnitudes and for the per-vertex
//! products of eq. (14), whose factors can under- or overflow f64 long before the
//! weights they feed do.
//!
//! A value is `m · 2^(512·steps)` with the mantissa `m` kept in [2⁻⁵⁰⁰, 2⁵⁰⁰] (or zero).
//! Scaling by a power of two is exact and commutes with rounding, so while every value
//! stays inside that range (`steps == 0`) each operation is the plain f64 operation,
//! bit for bit: a sum of densities between 1e-150 and 1e150 is exactly the naive sum in
//! the same order. Outside it nothing overflows: the exponent absorbs the excess.
//! No logarithms are taken on the way (only [`Scaled::ln`] calls one).

use crate::math;

/// 2^512, 2^-512 and the mantissa range, as exact powers of two.
const UP: f64 = f64::from_bits((1023 + 512) << 52);
const DOWN: f64 = f64::from_bits((1023 - 512) << 52);
const HIGH: f64 = f64::from_bits((1023 + 500) << 52);
const LOW: f64 = f64::from_bits((1023 - 500) << 52);
/// Five steps of 2^512 saturate any finite f64 to 0 or ∞.
const MAX_STEPS: i32 = 5;

/// `x · 2^(512·steps)`, saturating to 0 or ±∞.
#[inline]
fn scale2(mut x: f64, steps: i32) -> f64 {
    let factor = if steps > 0 { UP } else { DOWN };
    for _ in 0..steps.unsigned_abs().min(MAX_STEPS as u32) {
        x *= factor;
    }
    x
}

/// A non-negative number `m · 2^(512·steps)` that neither overflows nor underflows in
/// sums and products of densities. Invalid inputs (negative, NaN, infinite) enter as
/// zero: a technique that reports no finite density is skipped, never divided by.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Scaled {
    m: f64,
    steps: i32,
}

impl Scaled {
    /// Zero (the empty sum).
    pub const ZERO: Self = Self { m: 0.0, steps: 0 };
    /// One (the empty product).
    pub const ONE: Self = Self { m: 1.0, steps: 0 };

    /// `x` as a scaled value; zero unless `x` is finite and positive.
    #[inline]
    pub fn new(x: f64) -> Self {
        if x > 0.0 && x.is_finite() { Self { m: x, steps: 0 }.normalized() } else { Self::ZERO }
    }

    /// Bring the mantissa back into [2⁻⁵⁰⁰, 2⁵⁰⁰] (exact: powers of two only).
    #[inline]
    fn normalized(mut self) -> Self {
        if self.m == 0.0 {
            return Self::ZERO;
        }
        while self.m > HIGH {
            self.m *= DOWN;
            self.steps += 1;
        }
        while self.m < LOW {
            self.m *= UP;
            self.steps -= 1;
        }
        self
    }

    /// Whether the value is zero.
    #[inline]
    pub fn is_zero(self) -> bool {
        self.m == 0.0
    }

    /// The sum of two scaled values (the smaller is aligned to the larger's exponent).
    #[inline]
    pub fn plus(self, other: Self) -> Self {
        if self.is_zero() {
            return other;
        }
        if other.is_zero() {
            return self;
        }
        let (hi, lo) = if self.steps >= other.steps { (self, other) } else { (other, self) };
        Self { m: hi.m + scale2(lo.m, lo.steps - hi.steps), steps: hi.steps }.normalized()
    }

    /// Add one density term; terms that are not finite and positive are skipped.
    #[inline]
    pub fn add(&mut self, p: f64) {
        *self = self.plus(Self::new(p));
    }

    /// The product of two scaled values.
    #[inline]
    pub fn times(self, other: Self) -> Self {
        Self { m: self.m * other.m, steps: self.steps + other.steps }.normalized()
    }

    /// Σ of the finite positive terms of `terms` (eq. 6's inner sums).
    pub fn sum(terms: impl IntoIterator<Item = f64>) -> Self {
        terms.into_iter().fold(Self::ZERO, |mut s, p| {
            s.add(p);
            s
        })
    }

    /// Π of `factors`; zero as soon as one factor is not finite and positive.
    pub fn product(factors: impl IntoIterator<Item = Self>) -> Self {
        let mut acc = Self::ONE;
        for f in factors {
            if f.is_zero() {
                return Self::ZERO;
            }
            acc = acc.times(f);
        }
        acc
    }

    /// `self / other` as an f64 (saturating to 0 or ∞); zero when `other` is zero.
    #[inline]
    pub fn ratio(self, other: Self) -> f64 {
        if other.is_zero() {
            return 0.0;
        }
        // Both mantissas lie in [2⁻⁵⁰⁰, 2⁵⁰⁰], so their quotient is a normal f64.
        scale2(self.m / other.m, self.steps - other.steps)
    }

    /// `f / self` for a signed f64 numerator (an MMIS contribution f(x) / Σ p);
    /// zero when `self` is zero. Exactly `f / value` while both are in range.
    #[inline]
    pub fn divide(self, f: f64) -> f64 {
        let q = Self::new(f.abs()).ratio(self);
        if f < 0.0 { -q } else { q }
    }

    /// The value as an f64, saturating to 0 or ∞.
    #[inline]
    pub fn to_f64(self) -> f64 {
        scale2(self.m, self.steps)
    }

    /// Natural logarithm of the value (−∞ for zero), finite for every nonzero value.
    #[inline]
    pub fn ln(self) -> f64 {
        if self.is_zero() {
            return f64::NEG_INFINITY;
        }
        math::ln_f64(self.m) + (512 * self.steps) as f64 * core::f64::consts::LN_2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn in_range_arithmetic_is_plain_f64_bit_for_bit() {
        let xs = [3.7e-30, 1.0, 2.5e12, 7.1e-3, 9.9e29, 0.3];
        let mut s = Scaled::ZERO;
        let mut naive = 0.0f64;
        for &x in &xs {
            s.add(x);
            naive += x;
        }
        assert_eq!(s.to_f64().to_bits(), naive.to_bits());
        assert_eq!(s.divide(-1.25).to_bits(), (-1.25 / naive).to_bits());
        let p = Scaled::product(xs.iter().map(|&x| Scaled::new(x)));
        assert_eq!(p.to_f64().to_bits(), xs.iter().product::<f64>().to_bits());
    }

    #[test]
    fn sums_and_products_beyond_f64_stay_finite() {
        let mut s = Scaled::ZERO;
        for _ in 0..10 {
            s.add(f64::MAX);
        }
        assert!((s.ln() - (f64::MAX / 16.0 * 10.0).ln() - 16f64.ln()).abs() < 1e-10);
        assert!((Scaled::new(f64::MAX).ratio(s) - 0.1).abs() < 1e-15);
        let big = Scaled::product((0..20).map(|_| Scaled::new(1e30)));
        let tiny = Scaled::product((0..20).map(|_| Scaled::new(1e-30)));
        assert!((big.ln() - 600.0 * 10f64.ln()).abs() < 1e-9);
        assert!((big.times(tiny).to_f64() - 1.0).abs() < 1e-12);
        assert!((big.ratio(big.plus(big)) - 0.5).abs() < 1e-15);
        assert_eq!(big.to_f64(), f64::INFINITY);
        assert_eq!(tiny.to_f64(), 0.0);
    }

    #[test]
    fn invalid_terms_are_skipped_and_zero_is_never_divided_by() {
        let mut s = Scaled::ZERO;
        for p in [0.0, -1.0, f64::NAN, f64::INFINITY, -0.0] {
            s.add(p);
        }
        assert!(s.is_zero());
        assert_eq!(s.divide(3.0), 0.0);
        assert_eq!(Scaled::ONE.ratio(s), 0.0);
        assert_eq!(s.ln(), f64::NEG_INFINITY);
        s.add(2.0);
        assert_eq!(s.divide(3.0), 1.5);
    }
}
