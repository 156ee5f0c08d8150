//! Pixel reconstruction filters with Mitsuba 3's definitions (`src/rfilters/*.cpp`),
//! and the two ways the film applies them: camera samples by Mitsuba's weighted film,
//! splats by normalised weights.
//!
//! A filter is separable, f(x, y) = f(x) f(y), each factor with support [−r, r]:
//! - `box`: f = 1 on [−½, ½] (r = ½), one pixel; ember's filter before issue 25;
//! - `tent` (`radius` r, default 1): f(x) = max(0, 1 − |x|/r), ∫f = r;
//! - `gaussian` (`stddev` σ, default ½, r = 4σ): f(x) = max(0, g(x) − g(r)) with
//!   g(x) = exp(−x²/(2σ²)), so f reaches 0 at the cut-off;
//!   ∫_a^b g = σ√(π/2) (erf(b/(σ√2)) − erf(a/(σ√2))). Mitsuba evaluates it with a Remez
//!   polynomial fitted to the same function; we evaluate the exponential.
//!
//! # What a pixel is
//! Mitsuba's `hdrfilm` (`sample_border` false by default) draws film positions only in
//! the image rectangle F = [0, W) × [0, H) and its weighted film converges to
//!   I_c = ∫_F f(x − c) L(x) dx / ∫_F f(x − c) dx,                             (1)
//! c the pixel centre. Write h_c(x) = K_c f(x − c)/∫f with the per-pixel constant
//!   K_c = ∫f / ∫_F f(x − c) dx = Π_axes ∫f₁ / ∫_0^W f₁(x − c_x) dx             (2)
//! (separable), which is 1 wherever the filter's support lies inside F. Then
//! I_c = ∫_F h_c(x) L(x) dx and ∫_F h_c = 1: a normalised per-pixel measurement.
//!
//! # Camera samples: Mitsuba's weighted film
//! A camera sample's film point x is uniform in its pixel (the box's arithmetic, for
//! every filter), and the film adds f(x − c) L and f(x − c) to every pixel c within r of
//! x; each pixel's camera part is Σ f L / Σ f over all its passes, which converges to
//! eq. (1) (`crate::render::Film`; the essay on the estimator, a consistent ratio, is
//! in `render/film/spread.rs`). The box reaches one pixel with weight 1, so it keeps
//! `sum / passes` and every box image is unchanged bit for bit. Until issue 52 each
//! sample went to one pixel, its offset drawn from the filter (filter importance
//! sampling, weight h_c/p): unbiased, but each pixel then averaged one sample per pass
//! where the weighted film averages the 4–16 around it, and on `scenes-extra/textured`
//! it was 1.8–3.6× noisier per sample (docs/pixel-filters.md).
//!
//! # Splats
//! A splat at x ∈ F (light tracing, BDPT t = 1, ...) estimates the measurement density
//! at x, so it adds value · h_c(x) to every pixel c with |x − c| < r per axis
//! ([`Filter::splat_weight`]). The box reduces to the pixel containing x with weight 1.

use crate::math::{erf, exp};

/// √(π/2).
const SQRT_HALF_PI: f32 = 1.253_314_1;
/// g(r) = g(4σ) = exp(−8), the gaussian's cut-off value for every σ.
const EXP_MINUS_8: f32 = 3.354_626_3e-4;

/// A separable pixel reconstruction filter (see the module notes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Filter {
    /// One pixel, weight 1 (Mitsuba `box`, radius ½).
    Box,
    /// Mitsuba `tent`: 1 − |x|/radius.
    Tent {
        /// Half-width of the support, in pixels (> 0).
        radius: f32,
    },
    /// Mitsuba `gaussian`: exp(−x²/(2σ²)) − exp(−8), cut off at 4σ.
    Gaussian {
        /// σ, in pixels (> 0).
        stddev: f32,
    },
}

impl Default for Filter {
    /// The box: ember's historical filter (Mitsuba's default is [`Filter::MITSUBA_DEFAULT`]).
    fn default() -> Self {
        Self::Box
    }
}

impl Filter {
    /// What Mitsuba uses when a film names no `<rfilter>`: gaussian, σ = ½.
    pub const MITSUBA_DEFAULT: Filter = Filter::Gaussian { stddev: 0.5 };

    /// A tent of `radius` pixels; `None` unless finite and positive.
    pub fn tent(radius: f32) -> Option<Self> {
        (radius.is_finite() && radius > 0.0).then_some(Self::Tent { radius })
    }

    /// A gaussian of standard deviation `stddev` pixels; `None` unless finite and positive.
    pub fn gaussian(stddev: f32) -> Option<Self> {
        (stddev.is_finite() && stddev > 0.0 && (4.0 * stddev).is_finite()).then_some(Self::Gaussian { stddev })
    }

    /// Whether this is the box (the historical one-pixel path).
    #[inline]
    pub fn is_box(&self) -> bool {
        matches!(self, Self::Box)
    }

    /// Half-width r of the support, in pixels.
    #[inline]
    pub fn radius(&self) -> f32 {
        match *self {
            Self::Box => 0.5,
            Self::Tent { radius } => radius,
            Self::Gaussian { stddev } => 4.0 * stddev,
        }
    }

    /// The 1-D filter f(x) (unnormalised, Mitsuba's `eval`).
    #[inline]
    pub fn eval(&self, x: f32) -> f32 {
        match *self {
            Self::Box => {
                if x.abs() <= 0.5 {
                    1.0
                } else {
                    0.0
                }
            }
            Self::Tent { radius } => (1.0 - x.abs() / radius).max(0.0),
            Self::Gaussian { stddev } => (gauss(x, stddev) - EXP_MINUS_8).max(0.0),
        }
    }

    /// ∫_{−r}^{t} f (t clamped to the support).
    pub fn cdf(&self, t: f32) -> f32 {
        let r = self.radius();
        let t = t.clamp(-r, r);
        match *self {
            Self::Box => t + 0.5,
            Self::Tent { radius } => {
                if t <= 0.0 {
                    (radius + t) * (radius + t) / (2.0 * radius)
                } else {
                    radius - (radius - t) * (radius - t) / (2.0 * radius)
                }
            }
            Self::Gaussian { stddev } => {
                let s = stddev * core::f32::consts::SQRT_2;
                stddev * SQRT_HALF_PI * (erf(t / s) + erf(r / s)) - EXP_MINUS_8 * (t + r)
            }
        }
    }

    /// ∫f over the whole support.
    #[inline]
    pub fn integral(&self) -> f32 {
        self.cdf(self.radius())
    }

    /// K for one axis (eq. 2): ∫f / ∫_0^extent f(x − c) dx for a pixel centre c; exactly
    /// 1 where the support around c lies inside [0, extent].
    pub fn border_factor(&self, c: f32, extent: f32) -> f32 {
        let r = self.radius();
        if c - r >= 0.0 && c + r <= extent {
            return 1.0;
        }
        let inside = self.cdf(extent - c) - self.cdf(-c);
        if inside > 0.0 { self.integral() / inside } else { 0.0 }
    }

    /// h_c(x) along one axis: the share of a splat at coordinate `x` that pixel `i`
    /// (centre i + ½) of an axis of `extent` pixels receives.
    #[inline]
    pub fn splat_weight(&self, x: f32, i: u32, extent: u32) -> f32 {
        let c = i as f32 + 0.5;
        let f = self.eval(x - c);
        if f <= 0.0 {
            return 0.0;
        }
        f * self.border_factor(c, extent as f32) / self.integral()
    }

    /// The pixels along one axis of `extent` pixels that a splat at `x` reaches:
    /// those whose centre is within r of x.
    #[inline]
    pub fn splat_range(&self, x: f32, extent: u32) -> core::ops::Range<u32> {
        let r = self.radius();
        let lo = crate::math::ceil(x - 0.5 - r).max(0.0);
        let hi = (crate::math::floor(x - 0.5 + r) + 1.0).min(extent as f32);
        if hi > lo { lo as u32..hi as u32 } else { 0..0 }
    }
}

/// g(x) = exp(−x²/(2σ²)).
#[inline]
fn gauss(x: f32, stddev: f32) -> f32 {
    exp(-x * x / (2.0 * stddev * stddev))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cdf_integrates_eval() {
        for f in [Filter::Box, Filter::Tent { radius: 1.0 }, Filter::Tent { radius: 1.7 }, Filter::Gaussian { stddev: 0.5 }, Filter::Gaussian { stddev: 1.3 }] {
            let r = f.radius();
            let n = 4000;
            let h = 2.0 * r / n as f32;
            let riemann: f32 = (0..n).map(|i| f.eval(-r + (i as f32 + 0.5) * h) * h).sum();
            assert!((riemann - f.integral()).abs() < 1e-3 * f.integral(), "{f:?}: {riemann} vs {}", f.integral());
            assert!((f.cdf(0.0) - 0.5 * f.integral()).abs() < 1e-5, "{f:?}");
        }
        assert_eq!(Filter::Gaussian { stddev: 0.5 }.border_factor(10.0, 20.0), 1.0);
        assert!(Filter::Gaussian { stddev: 0.5 }.border_factor(0.5, 20.0) > 1.0);
        assert_eq!(Filter::Box.border_factor(0.5, 1.0), 1.0);
    }
}
