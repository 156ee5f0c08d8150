//! Γ, the subspace sampling matrix [SPCBPT eq. 7, section 7.3].
//!
//! Γ(l | e) is the probability that an eye sub-path in eye subspace `e` connects to a light
//! sub-path drawn from light subspace `l`; each eye column is a pmf over light subspaces
//! (the paper's "left stochastic" matrix). It is parametrised by an unconstrained matrix
//! Θ through a sigmoid and a column normalisation, then mixed with a uniform pmf as
//! defensive sampling (section 7.3, "10% uniform"):
//!
//! ```text
//! s_le = σ(Θ_le),  S_e = Σ_l s_le,  p_le = s_le / S_e,
//! Γ_le = (1 − m)·p_le + m / n_light.
//! ```
//!
//! Storage is eye-major (`index = e·n_light + l`), so a column — the pmf the renderer
//! samples for one eye subspace — is a contiguous slice, and a host can refresh Γ for a
//! range of eye subspaces in parallel by calling [`gamma_from_theta`] on sub-slices.
//!
//! Robustness: Θ is read through [`clamp_theta`] (NaN → −30, ±∞ and |Θ| > 30 → ±30), so
//! σ is never exactly 0, every column sum is ≥ n_light·σ(−30) > 0 and Γ is always finite
//! with columns summing to one (up to f32 rounding). The gradient in `loss.rs` uses the
//! same clamped Θ, so loss and gradient describe the same function.

use alloc::vec;
use alloc::vec::Vec;

/// Largest |Θ| the sigmoid is evaluated at; σ(±30) is 1 − 9e-14 / 9e-14, i.e. saturated.
pub const THETA_LIMIT: f32 = 30.0;

/// Θ as the sigmoid sees it: clamped to ±[`THETA_LIMIT`], NaN → −THETA_LIMIT (a NaN
/// parameter carries no information; the smallest weight is the safe reading).
#[inline]
#[allow(clippy::manual_clamp)] // max/min map NaN to a bound; `clamp` would keep the NaN.
pub fn clamp_theta(theta: f32) -> f32 {
    theta.max(-THETA_LIMIT).min(THETA_LIMIT)
}

/// eˣ for |x| ≤ 44 (wider input is clamped), relative error < 1e-6: n = round(x·log₂e)
/// (round-to-nearest by the 1.5·2²³ trick), r = x − n·ln 2 in two parts (Cody–Waite, so r
/// keeps full precision), eʳ for |r| ≤ 0.347 by its degree-6 Taylor polynomial (truncation
/// 0.347⁷/7! ≈ 1.2e-7) and 2ⁿ by the exponent bits. Pure arithmetic without branches, so
/// the column loops vectorise: Γ is refreshed (10⁶ sigmoids at N_S = 1000) after every Adam
/// step, where libm's scalar `expf` dominated the epoch. Not a float intrinsic, so it lives
/// here with its only user rather than in `math`.
#[inline]
#[allow(clippy::manual_clamp)] // max/min map NaN to a bound; `clamp` would keep the NaN.
fn exp_bounded(x: f32) -> f32 {
    const SHIFTER: f32 = 12_582_912.0; // 1.5·2²³
    const LN2_HI: f32 = 0.693_145_751_953_125; // ln 2 rounded to 16 significant bits
    const LN2_LO: f32 = 1.428_606_765_330_187e-6; // ln 2 − LN2_HI
    let x = x.max(-44.0).min(44.0);
    let shifted = x * core::f32::consts::LOG2_E + SHIFTER;
    let n = shifted - SHIFTER;
    let r = (x - n * LN2_HI) - n * LN2_LO;
    let p = 1.0 + r * (1.0 + r * (0.5 + r * (1.0 / 6.0 + r * (1.0 / 24.0 + r * (1.0 / 120.0 + r * (1.0 / 720.0))))));
    // shifted's low mantissa bits hold 2²² + n; shifting them into the exponent field
    // drops the 2²² (2⁴⁵ wraps to 0) and leaves n in two's complement: 2ⁿ without a
    // float→int conversion (whose saturation checks would stop vectorisation).
    let scale = f32::from_bits((shifted.to_bits() << 23).wrapping_add(127 << 23));
    p * scale
}

/// The logistic sigmoid σ(Θ) = 1/(1 + e^(−Θ)) of the clamped Θ: never 0 (≥ 9.3e-14),
/// relative error < 1e-6. Γ and the gradient both use this one function.
#[inline]
pub fn sigmoid(theta: f32) -> f32 {
    1.0 / (1.0 + exp_bounded(-clamp_theta(theta)))
}

/// (σ(Θ), σ'(Θ)) with σ' = e^(−Θ)·σ² — not σ(1 − σ), which is 0 in f32 once σ rounds to 1
/// (Θ ≳ 17) and would freeze those parameters. Same clamping as [`sigmoid`].
#[inline]
pub fn sigmoid_and_derivative(theta: f32) -> (f32, f32) {
    let e = exp_bounded(-clamp_theta(theta));
    let s = 1.0 / (1.0 + e);
    (s, e * s * s)
}

/// Σ_l σ(Θ_l) over one column in f64, with eight independent accumulators so the loop
/// vectorises (a single running f64 sum is a serial dependency chain).
#[inline]
pub fn column_sigmoid_sum(theta_column: &[f32]) -> f64 {
    let mut lanes = [0.0f64; 8];
    let chunks = theta_column.chunks_exact(8);
    let rest = chunks.remainder();
    for chunk in chunks {
        for (lane, &t) in lanes.iter_mut().zip(chunk) {
            *lane += sigmoid(t) as f64;
        }
    }
    let tail: f64 = rest.iter().map(|&t| sigmoid(t) as f64).sum();
    lanes.iter().sum::<f64>() + tail
}

/// Γ from Θ (both eye-major, length `n_light·n_eye`) with uniform `mixture` m ∈ [0, 1]:
/// `Γ = (1 − m)·σ(Θ_le)/Σ_l' σ(Θ_l'e) + m / n_light`. Writes `out`; if a slice is too
/// short only the complete columns that fit are written.
pub fn gamma_from_theta(theta: &[f32], n_light: usize, n_eye: usize, mixture: f32, out: &mut [f32]) {
    if n_light == 0 {
        return;
    }
    let m = mixture.clamp(0.0, 1.0) as f64;
    let uniform = m / n_light as f64;
    let columns = n_eye.min(theta.len() / n_light).min(out.len() / n_light);
    for e in 0..columns {
        let th = &theta[e * n_light..(e + 1) * n_light];
        let col = &mut out[e * n_light..(e + 1) * n_light];
        let sum = column_sigmoid_sum(th);
        let scale = ((1.0 - m) / sum) as f32;
        let uniform = uniform as f32;
        for (g, &t) in col.iter_mut().zip(th) {
            *g = sigmoid(t) * scale + uniform;
        }
    }
}

/// Γ with its dimensions: `get(l, e)` = Γ(l | e); columns are pmfs over light subspaces.
#[derive(Clone, Debug)]
pub struct SubspaceMatrix {
    n_light: usize,
    n_eye: usize,
    /// Eye-major: `gamma[e·n_light + l]`.
    gamma: Vec<f32>,
}

impl SubspaceMatrix {
    /// Γ from a trained Θ (eye-major) with the render-time uniform `mixture`.
    pub fn from_theta(theta: &[f32], n_light: usize, n_eye: usize, mixture: f32) -> Self {
        let mut gamma = vec![0.0f32; n_light * n_eye];
        if theta.len() >= n_light * n_eye {
            gamma_from_theta(theta, n_light, n_eye, mixture, &mut gamma);
        } else {
            // Missing Θ entries read as 0 (σ = 1/2): pad rather than panic.
            let mut padded = vec![0.0f32; n_light * n_eye];
            padded[..theta.len()].copy_from_slice(theta);
            gamma_from_theta(&padded, n_light, n_eye, mixture, &mut gamma);
        }
        Self { n_light, n_eye, gamma }
    }

    /// The uniform Γ(l | e) = 1 / n_light.
    pub fn uniform(n_light: usize, n_eye: usize) -> Self {
        let value = if n_light == 0 { 0.0 } else { 1.0 / n_light as f32 };
        Self { n_light, n_eye, gamma: vec![value; n_light * n_eye] }
    }

    /// Γ from an explicit eye-major matrix (for tests and hosts that load Γ).
    pub fn from_gamma(gamma: Vec<f32>, n_light: usize, n_eye: usize) -> Self {
        let mut gamma = gamma;
        gamma.resize(n_light * n_eye, 0.0);
        Self { n_light, n_eye, gamma }
    }

    /// Number of light subspaces (rows).
    pub fn n_light(&self) -> usize {
        self.n_light
    }

    /// Number of eye subspaces (columns).
    pub fn n_eye(&self) -> usize {
        self.n_eye
    }

    /// Γ(light | eye); 0 out of range.
    #[inline]
    pub fn get(&self, light: u32, eye: u32) -> f32 {
        let (l, e) = (light as usize, eye as usize);
        if l >= self.n_light || e >= self.n_eye {
            return 0.0;
        }
        self.gamma[e * self.n_light + l]
    }

    /// The pmf over light subspaces for eye subspace `eye` (empty slice out of range).
    #[inline]
    pub fn column(&self, eye: u32) -> &[f32] {
        let e = eye as usize;
        if e >= self.n_eye {
            return &[];
        }
        &self.gamma[e * self.n_light..(e + 1) * self.n_light]
    }

    /// The whole eye-major matrix.
    pub fn as_slice(&self) -> &[f32] {
        &self.gamma
    }

    /// Heap bytes held.
    pub fn size_bytes(&self) -> usize {
        self.gamma.capacity() * core::mem::size_of::<f32>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The polynomial sigmoid against the f64 definition over the whole clamped range.
    #[test]
    fn sigmoid_is_accurate_and_saturates_safely() {
        let mut worst = 0.0f64;
        for k in -40_000..=40_000 {
            let t = k as f32 * 1e-3;
            let exact = 1.0 / (1.0 + libm::exp(-(t.clamp(-30.0, 30.0)) as f64));
            let rel = (sigmoid(t) as f64 - exact).abs() / exact;
            worst = worst.max(rel);
        }
        assert!(worst < 1e-6, "worst relative error {worst:e}");
        for t in [-29.0f32, -3.0, 0.0, 2.0, 17.0, 25.0] {
            let (s, d) = sigmoid_and_derivative(t);
            let e = libm::exp(-(t as f64));
            let exact = e / ((1.0 + e) * (1.0 + e));
            assert_eq!(s, sigmoid(t));
            assert!((d as f64 - exact).abs() < 1e-5 * exact, "σ'({t}) = {d}, exact {exact}");
        }
        for t in [f32::INFINITY, f32::NEG_INFINITY, f32::NAN, 1e30, -1e30] {
            let s = sigmoid(t);
            assert!(s > 0.0 && s <= 1.0, "σ({t}) = {s}");
        }
    }
}
