//! Adam [Kingma and Ba 2014], as used for Θ in [SPCBPT section 7.3].
//!
//! ```text
//! m ← β₁m + (1 − β₁)g,  v ← β₂v + (1 − β₂)g²,
//! θ ← θ − α·m̂/(√v̂ + ε),  m̂ = m/(1 − β₁ᵗ), v̂ = v/(1 − β₂ᵗ).
//! ```
//!
//! Moments live in f64 (gradients of f²/p-weighted losses span many decades). Robustness
//! rules: a non-finite gradient entry counts as 0; g² that overflows is capped so v stays
//! finite; a step that would make θ non-finite is dropped for that entry; θ is clamped to
//! ±[`THETA_LIMIT`](super::subspace_matrix::THETA_LIMIT), where the sigmoid is saturated
//! anyway, so Θ can never run off to infinity on an outlier.

use alloc::vec;
use alloc::vec::Vec;

use super::subspace_matrix::THETA_LIMIT;

/// Adam's hyper-parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdamParams {
    /// Step size α.
    pub learning_rate: f32,
    /// First-moment decay β₁.
    pub beta1: f32,
    /// Second-moment decay β₂.
    pub beta2: f32,
    /// ε in the denominator.
    pub epsilon: f32,
}

impl Default for AdamParams {
    /// The paper's values: α = 0.1, β = (0.9, 0.999), ε = 1e-8.
    fn default() -> Self {
        Self { learning_rate: 0.1, beta1: 0.9, beta2: 0.999, epsilon: 1e-8 }
    }
}

/// Adam state for `n` parameters.
#[derive(Clone, Debug)]
pub struct Adam {
    m: Vec<f64>,
    v: Vec<f64>,
    t: u32,
    params: AdamParams,
}

impl Adam {
    /// Fresh state (zero moments) for `n` parameters.
    pub fn new(n: usize, params: AdamParams) -> Self {
        Self { m: vec![0.0; n], v: vec![0.0; n], t: 0, params }
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u32 {
        self.t
    }

    /// Heap bytes held.
    pub fn size_bytes(&self) -> usize {
        (self.m.capacity() + self.v.capacity()) * 8
    }

    /// One step on caller-owned `params` with gradient `grad`; only the first
    /// min(n, params.len(), grad.len()) entries are touched. Non-finite gradient entries
    /// count as 0, and no parameter ever becomes non-finite (|θ| ≤ THETA_LIMIT).
    pub fn step(&mut self, params: &mut [f32], grad: &[f64]) {
        self.t = self.t.saturating_add(1);
        let b1 = self.params.beta1 as f64;
        let b2 = self.params.beta2 as f64;
        let lr = self.params.learning_rate as f64;
        let eps = self.params.epsilon as f64;
        let t = self.t as f64;
        let bias1 = 1.0 - crate::math::exp_f64(t * crate::math::ln_f64(b1));
        let bias2 = 1.0 - crate::math::exp_f64(t * crate::math::ln_f64(b2));
        let (bias1, bias2) = (bias1.max(f64::MIN_POSITIVE), bias2.max(f64::MIN_POSITIVE));
        let limit = THETA_LIMIT as f64;
        let n = self.m.len().min(params.len()).min(grad.len());
        for i in 0..n {
            let g = if grad[i].is_finite() { grad[i] } else { 0.0 };
            // Cap |g| so g² stays finite (1e150² = 1e300).
            let g = g.clamp(-1e150, 1e150);
            self.m[i] = b1 * self.m[i] + (1.0 - b1) * g;
            self.v[i] = b2 * self.v[i] + (1.0 - b2) * g * g;
            let m_hat = self.m[i] / bias1;
            let v_hat = self.v[i] / bias2;
            let step = lr * m_hat / (crate::math::sqrt_f64(v_hat) + eps);
            let current = if params[i].is_finite() { params[i] as f64 } else { 0.0 };
            let next = current - step;
            if next.is_finite() {
                params[i] = next.clamp(-limit, limit) as f32;
            } else {
                params[i] = current.clamp(-limit, limit) as f32;
            }
        }
    }
}
