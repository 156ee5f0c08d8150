//! Camera samples spread over the pixels of a wide filter's support: Mitsuba's weighted
//! film (`hdrfilm` with a `tent` or `gaussian` `rfilter`), in exact sums.
//!
//! # What is estimated
//! A camera sample of pixel p lies at a film point x uniform in p ([`camera_film_point`]).
//! It is added to every pixel c whose centre is within the filter's radius r of x, per
//! axis, with the weight w_c(x) = f(x − c) = f₁(x_x − c_x) f₁(x_y − c_y): Σ w L to the
//! pixel's numerator, Σ w to its denominator ([`WeightedSum`]). The image is their ratio,
//!   Î_c = Σ_k w_c(x_k) L_k / Σ_k w_c(x_k),                                         (1)
//! over every sample k of every pass that reaches c. Over many passes the numerator
//! divided by the number of passes tends to ∫_F f(x − c) L(x) dx and the denominator to
//! ∫_F f(x − c) dx (the film points of one pass tile F = [0, W) × [0, H) uniformly), so
//! Î_c tends to `crate::pixel_filter`'s I_c (eq. 1 there), the value splats estimate.
//!
//! # Bias and consistency
//! (1) is a ratio estimator: consistent, not unbiased. E[N/D] ≠ E[N]/E[D]; the bias is
//! O(1/n) in the number n of passes (first order (E[N] Var D/E[D]² − Cov(N, D)/E[D]) /
//! (n E[D]), with N, D one pass's sums), so it vanishes as the render goes on, and it is
//! zero where L is constant over the support: there (1) returns L exactly, whatever the
//! weights. Mitsuba's film makes the same trade. We take it for the variance: each pixel
//! averages the 4 (tent, r = 1) to 16 (gaussian, σ = ½) samples around it instead of one,
//! and the weights' own noise cancels between numerator and denominator. Filter
//! importance sampling (ember before issue 52: one sample per pixel, its offset drawn
//! from the filter) is unbiased but was 1.8–3.6× noisier per sample on
//! `scenes-extra/textured` (docs/pixel-filters.md). The unbiased spread, Σ w L divided
//! by the expected Σ w instead of the drawn one, keeps the weights' noise; we did not
//! take it.
//!
//! # Data flow
//! Estimators stage one value per pixel per pass, as for the box, and the film spreads
//! them when the pass is committed. Film points travel in no chunk: the film draws them
//! again from the pass's [`CameraPass`], the first 2-D number of the pixel's camera
//! stream, the one every estimator's camera sample draws first
//! (`PerspectiveCamera::sample_ray`). So each estimator's chunks, wire format and film
//! write are the box's, and a pass still commits whole (a pixel's sums take its
//! neighbours' samples of the same pass, staged before the commit).
//!
//! # Exactness
//! Every weighted addition f · L and every weight f is rounded on its own to the film's
//! quantum and added as an integer, like a splat's, so the sums do not depend on the
//! order of additions: a band of rows ([`super::bands`]) reads the staged samples of the
//! rows around it and adds only to its own rows, and any thread count, any grouping of
//! passes and any merge of films give the same bits. An invalid sample (NaN, infinite,
//! negative) counts as zero: its weights are still added and it is tallied once, by the
//! band that holds its pixel.

use core::ops::Range;

use super::{Tallies, add, to_fixed};
use crate::camera::{CameraPass, camera_film_point};
use crate::math;
use crate::pixel_filter::Filter;
use crate::spectrum::Rgb;

/// A pixel's camera samples under a wide filter, in units of 2⁻⁶⁴
/// ([`super::QUANTUM_BITS`]): Σ f(x − c) L per channel and Σ f(x − c) (eq. 1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WeightedSum {
    /// Σ w L, per channel.
    pub value: [u128; 3],
    /// Σ w.
    pub weight: u128,
}

impl WeightedSum {
    /// Eq. (1) for channel `c`: 0 where no sample reached the pixel.
    #[inline]
    pub fn ratio(&self, c: usize) -> f64 {
        if self.weight == 0 { 0.0 } else { self.value[c] as f64 / self.weight as f64 }
    }

    /// Add `other`'s sums; returns how many of the four saturated (stayed at the top).
    pub(super) fn merge(&mut self, other: &WeightedSum) -> u64 {
        let mut saturated = 0;
        for (a, b) in self.value.iter_mut().chain(core::iter::once(&mut self.weight)).zip(other.value.iter().chain(core::iter::once(&other.weight))) {
            *a = a.checked_add(*b).unwrap_or_else(|| {
                saturated += 1;
                u128::MAX
            });
        }
        saturated
    }

    /// Add a sample `v` with weight `w` > 0; returns how many sums saturated.
    #[inline]
    fn add(&mut self, v: Rgb, w: f32) -> u64 {
        let mut saturated = add(&mut self.value, v, w as f64);
        match to_fixed(w as f64).and_then(|n| self.weight.checked_add(n)) {
            Some(s) => self.weight = s,
            None => {
                self.weight = u128::MAX;
                saturated += 1;
            }
        }
        saturated
    }
}

/// Spread the staged camera samples `camera` (the whole `width × height` image, of pass
/// `at`) over the pixels of rows `rows` they reach under `filter`; `sums` holds exactly
/// those rows. Invalid samples of rows `rows` are tallied in `tallies`.
#[allow(clippy::too_many_arguments)]
pub(super) fn spread_camera_rows(
    filter: Filter,
    at: CameraPass,
    width: u32,
    height: u32,
    camera: &[Rgb],
    sums: &mut [WeightedSum],
    rows: Range<u32>,
    tallies: &mut Tallies,
) {
    // A sample of row y lies in [y, y + 1) and reaches the rows whose centre is within r
    // of it: rows y − k with k + ½ < r + 1, that is k ≤ ⌈r + ½⌉ − 1.
    let reach = (math::ceil(filter.radius() + 0.5) as u32).saturating_sub(1);
    let sources = rows.start.saturating_sub(reach)..rows.end.saturating_add(reach).min(height);
    // The filter along x of the sample at hand, evaluated once per sample (the taps of
    // filters up to 8 pixels wide; wider ones evaluate at every pixel).
    let mut taps = [0.0f32; TAPS];
    for sy in sources {
        for sx in 0..width {
            let p = sy * width + sx;
            let mut v = camera[p as usize];
            if !v.is_valid_radiance() {
                if rows.contains(&sy) {
                    tallies.discarded += 1;
                }
                v = Rgb::ZERO;
            }
            let x = camera_film_point(at, p, width);
            let columns = filter.splat_range(x.x, width);
            let tapped = columns.len() <= TAPS;
            if tapped {
                for (t, px) in taps.iter_mut().zip(columns.clone()) {
                    *t = filter.eval(x.x - (px as f32 + 0.5));
                }
            }
            let filter_rows = filter.splat_range(x.y, height);
            for py in filter_rows.start.max(rows.start)..filter_rows.end.min(rows.end) {
                let wy = filter.eval(x.y - (py as f32 + 0.5));
                if wy <= 0.0 {
                    continue;
                }
                let row = (py - rows.start) as usize * width as usize;
                for (k, px) in columns.clone().enumerate() {
                    let wx = if tapped { taps[k] } else { filter.eval(x.x - (px as f32 + 0.5)) };
                    let w = wy * wx;
                    if w > 0.0 {
                        tallies.saturated += sums[row + px as usize].add(v, w);
                    }
                }
            }
        }
    }
}

/// Filter taps along x kept per sample: a support up to 8 pixels wide (a gaussian of
/// σ ≤ 1, a tent of radius ≤ 4).
const TAPS: usize = 9;
