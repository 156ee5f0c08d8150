//! The MIS-aware loss for Γ and its gradient with respect to Θ [SPCBPT eq. 15-16, section 7.3].
//!
//! For a dataset path x sampled with pdf p(x), eq. 15 gives the second-moment bound
//! `f²(x) / (p(x)·F(x|Γ))` with the balance-heuristic denominator of eq. 12/16
//!
//! ```text
//! F(x|Γ) = g₀(x) + Σ_splits c_s·Γ(l_s | e_s),   c_s = N·p(Z̄)·f_y(Ȳ)/Q(κ_L(Ȳ))   [eq. 7, 11]
//! ```
//!
//! where g₀ ("fixed") sums n_t·p_t over the strategies Γ does not touch (t ∈ {0, 1, k+1})
//! and each split t ≥ 2 of x contributes its connection pdf. The caller stores
//! `weight = f²/p` (relative contribution, already clamped), `fixed = g₀` and the splits;
//! the loss is `L = Σ_x w_x / F_x`, convex in Γ.
//!
//! Gradient (derivation in docs/spcbpt-training.md). With s = σ(Θ), S_e = Σ_l s_le,
//! p_le = s_le/S_e and Γ_le = (1 − m)·p_le + m/n_light:
//!
//! ```text
//! G_le   = ∂L/∂Γ_le = −Σ_x (w_x/F_x²)·Σ_{s∈x: (l_s,e_s)=(l,e)} c_s
//! ∂Γ_le/∂s_l'e = (1 − m)·(δ_ll' − p_le)/S_e
//! ∂L/∂Θ_le = (1 − m)·σ'(Θ_le)/S_e · (G_le − B_e),   B_e = Σ_l G_le·p_le,  σ' = s(1 − s)
//!                                          (evaluated as e^(−Θ)·s², exact where s rounds to 1)
//! ```
//!
//! The mixture enters the gradient twice: in F (the loss is evaluated on the mixed Γ the
//! renderer will use) and as the factor (1 − m) of ∂Γ/∂p. The public OptiX-7 code drops
//! the latter. For Adam a uniform scale is almost invisible (it normalises per parameter,
//! up to ε), but the gradient is then simply wrong — a finite-difference test pins it —
//! and any scale-sensitive optimiser (SGD, clipping, ε-dominated steps) would mis-step.
//! G is sparse
//! (only the cells a batch's splits touch), the B_e term is dense over each touched column,
//! so one call costs O(splits + n_light·touched columns) and needs only a per-eye scratch.

use alloc::vec;
use alloc::vec::Vec;
use core::ops::Range;

use super::subspace_matrix::{column_sigmoid_sum, sigmoid, sigmoid_and_derivative};

/// One Γ-dependent strategy (a split t ≥ 2) of a dataset path: it contributes
/// `coef·Γ(light | eye)` to F.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct TrainingSplit {
    /// Eye subspace κ_E(Z̄) of the split's eye sub-path.
    pub eye: u32,
    /// Light subspace κ_L(Ȳ) of the split's light sub-path.
    pub light: u32,
    /// N·p(Z̄)·f_y(Ȳ)/Q(κ_L(Ȳ)).
    pub coef: f64,
}

/// The training dataset in flat arrays (struct of arrays; splits of path i are
/// `splits[split_start[i]..split_start[i + 1]]`).
#[derive(Clone, Debug)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct TrainingSet {
    weights: Vec<f64>,
    fixed: Vec<f64>,
    split_start: Vec<u32>,
    splits: Vec<TrainingSplit>,
}

impl Default for TrainingSet {
    fn default() -> Self {
        Self::new()
    }
}

impl TrainingSet {
    /// An empty set.
    pub fn new() -> Self {
        Self { weights: Vec::new(), fixed: Vec::new(), split_start: vec![0], splits: Vec::new() }
    }

    /// An empty set with room for `paths` paths and `splits` splits.
    pub fn with_capacity(paths: usize, splits: usize) -> Self {
        let mut split_start = Vec::with_capacity(paths + 1);
        split_start.push(0);
        Self { weights: Vec::with_capacity(paths), fixed: Vec::with_capacity(paths), split_start, splits: Vec::with_capacity(splits) }
    }

    /// Append one path: `weight = f²/p`, `fixed = g₀`, its Γ-dependent splits.
    pub fn push_path(&mut self, weight: f64, fixed: f64, splits: &[TrainingSplit]) {
        self.weights.push(weight);
        self.fixed.push(fixed);
        self.splits.extend_from_slice(splits);
        self.split_start.push(self.splits.len() as u32);
    }

    /// Append every path of `other` (hosts fill per-thread sets and merge them in order).
    pub fn append(&mut self, other: &TrainingSet) {
        let base = self.splits.len() as u32;
        self.weights.extend_from_slice(&other.weights);
        self.fixed.extend_from_slice(&other.fixed);
        self.split_start.extend(other.split_start[1..].iter().map(|&s| s + base));
        self.splits.extend_from_slice(&other.splits);
    }

    /// Remove every path, keeping the capacity.
    pub fn clear(&mut self) {
        self.weights.clear();
        self.fixed.clear();
        self.split_start.clear();
        self.split_start.push(0);
        self.splits.clear();
    }

    /// Number of paths.
    pub fn len(&self) -> usize {
        self.weights.len()
    }

    /// True when no path is stored.
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }

    /// Total number of splits.
    pub fn split_count(&self) -> usize {
        self.splits.len()
    }

    /// Path `i`'s weight f²/p (0 out of range).
    pub fn weight(&self, i: usize) -> f64 {
        self.weights.get(i).copied().unwrap_or(0.0)
    }

    /// Path `i`'s Γ-independent denominator g₀ (0 out of range).
    pub fn fixed(&self, i: usize) -> f64 {
        self.fixed.get(i).copied().unwrap_or(0.0)
    }

    /// Path `i`'s splits (empty out of range).
    pub fn splits(&self, i: usize) -> &[TrainingSplit] {
        match (self.split_start.get(i), self.split_start.get(i + 1)) {
            (Some(&a), Some(&b)) => &self.splits[a as usize..b as usize],
            _ => &[],
        }
    }

    /// Heap bytes held.
    pub fn size_bytes(&self) -> usize {
        self.weights.capacity() * 8
            + self.fixed.capacity() * 8
            + self.split_start.capacity() * 4
            + self.splits.capacity() * core::mem::size_of::<TrainingSplit>()
    }
}

/// F(x|Γ) for path `i` (`None` if a split's subspace is out of range).
#[inline]
fn denominator(set: &TrainingSet, i: usize, gamma: &[f32], n_light: usize, n_eye: usize) -> Option<f64> {
    let mut f = set.fixed[i];
    for s in set.splits(i) {
        let (l, e) = (s.light as usize, s.eye as usize);
        if l >= n_light || e >= n_eye {
            return None;
        }
        f += s.coef * gamma[e * n_light + l] as f64;
    }
    Some(f)
}

/// The loss `Σ w/F` alone over `paths` (no gradient); returns (loss, skipped).
pub fn loss_only(set: &TrainingSet, paths: Range<usize>, gamma: &[f32], n_light: usize, n_eye: usize) -> (f64, usize) {
    let end = paths.end.min(set.len());
    let mut loss = 0.0;
    let mut skipped = 0;
    if gamma.len() < n_light * n_eye {
        return (0.0, end.saturating_sub(paths.start));
    }
    for i in paths.start..end {
        match path_term(set, i, gamma, n_light, n_eye) {
            Some((term, _)) => loss += term,
            None => skipped += 1,
        }
    }
    (loss, skipped)
}

/// (w/F, ∂(w/F)/∂F) for path `i`, or `None` if the path must be skipped
/// (F ≤ 0, a negative or non-finite weight, any non-finite term).
#[inline]
fn path_term(set: &TrainingSet, i: usize, gamma: &[f32], n_light: usize, n_eye: usize) -> Option<(f64, f64)> {
    let w = set.weights[i];
    if !(w >= 0.0 && w.is_finite()) {
        return None;
    }
    let f = denominator(set, i, gamma, n_light, n_eye)?;
    if !(f > 0.0 && f.is_finite()) {
        return None;
    }
    let term = w / f;
    let d_term = -term / f;
    if !(term.is_finite() && d_term.is_finite()) {
        return None;
    }
    // Every split's gradient dF·c must be finite too.
    for s in set.splits(i) {
        if !(d_term * s.coef).is_finite() {
            return None;
        }
    }
    Some((term, d_term))
}

/// Loss `Σ w/F` over `paths` and its gradient w.r.t. Θ ADDED into `grad`
/// (len n_light·n_eye, eye-major), through the mixture and the column normalisation;
/// `gamma` must be [`super::gamma_from_theta`]'s output for the same `theta` and `mixture`.
/// Paths with F ≤ 0, out-of-range subspaces or non-finite terms are skipped and counted.
/// Returns (loss, skipped).
#[allow(clippy::too_many_arguments)]
pub fn loss_and_gradient(
    set: &TrainingSet,
    paths: Range<usize>,
    theta: &[f32],
    gamma: &[f32],
    n_light: usize,
    n_eye: usize,
    mixture: f32,
    grad: &mut [f64],
) -> (f64, usize) {
    let end = paths.end.min(set.len());
    let start = paths.start.min(end);
    loss_and_gradient_over(set, start..end, theta, gamma, n_light, n_eye, mixture, grad)
}

/// [`loss_and_gradient`] over an explicit list of path indices (a shuffled mini-batch);
/// indices past the set's end are skipped and counted.
#[allow(clippy::too_many_arguments)]
pub fn loss_and_gradient_indexed(
    set: &TrainingSet,
    paths: &[u32],
    theta: &[f32],
    gamma: &[f32],
    n_light: usize,
    n_eye: usize,
    mixture: f32,
    grad: &mut [f64],
) -> (f64, usize) {
    loss_and_gradient_over(set, paths.iter().map(|&i| i as usize), theta, gamma, n_light, n_eye, mixture, grad)
}

/// S_e = Σ_l σ(Θ_le) recovered from the current Γ column with one sigmoid:
/// Γ_l − m/n = (1 − m)·s_l/S_e, read at the column's largest Γ (≥ 1/n, so Γ − m/n ≥
/// (1 − m)/n and the subtraction loses at most a factor 1/(1 − m) of f32 precision).
/// Falls back to the full sum when that is ill-conditioned (m near 1) — saving one of the
/// two n_light-sigmoid passes per touched column.
fn column_sum_from_gamma(theta_column: &[f32], gamma_column: &[f32], mixture: f32) -> f64 {
    let m = mixture.clamp(0.0, 1.0) as f64;
    let n = gamma_column.len() as f64;
    let (mut best, mut at) = (f32::NEG_INFINITY, 0usize);
    for (l, &g) in gamma_column.iter().enumerate() {
        if g > best {
            best = g;
            at = l;
        }
    }
    let excess = best as f64 - m / n;
    if m < 0.9 && excess > 0.5 * (1.0 - m) / n {
        let sum = (1.0 - m) * sigmoid(theta_column[at]) as f64 / excess;
        if sum.is_finite() && sum > 0.0 {
            return sum;
        }
    }
    column_sigmoid_sum(theta_column)
}

#[allow(clippy::too_many_arguments)]
fn loss_and_gradient_over(
    set: &TrainingSet,
    paths: impl Iterator<Item = usize>,
    theta: &[f32],
    gamma: &[f32],
    n_light: usize,
    n_eye: usize,
    mixture: f32,
    grad: &mut [f64],
) -> (f64, usize) {
    let cells = n_light * n_eye;
    if theta.len() < cells || gamma.len() < cells || grad.len() < cells || n_light == 0 {
        return (0.0, paths.count());
    }
    let one_minus_m = 1.0 - mixture.clamp(0.0, 1.0) as f64;
    // Per eye column: S_e (0 = not computed yet) and B_e = Σ_l G_le·p_le.
    let mut column_sum = vec![0.0f64; n_eye];
    let mut column_b = vec![0.0f64; n_eye];
    let mut touched: Vec<u32> = Vec::new();
    let mut loss = 0.0;
    let mut skipped = 0;

    // Step 1: per path, the loss term and the sparse part (1 − m)·σ'/S·G; collect B_e.
    for i in paths {
        if i >= set.len() {
            skipped += 1;
            continue;
        }
        let Some((term, d_term)) = path_term(set, i, gamma, n_light, n_eye) else {
            skipped += 1;
            continue;
        };
        loss += term;
        for s in set.splits(i) {
            let (l, e) = (s.light as usize, s.eye as usize);
            if column_sum[e] == 0.0 {
                column_sum[e] = column_sum_from_gamma(&theta[e * n_light..(e + 1) * n_light], &gamma[e * n_light..(e + 1) * n_light], mixture);
                touched.push(e as u32);
            }
            let sum = column_sum[e];
            let g = d_term * s.coef;
            let (sig, d_sig) = sigmoid_and_derivative(theta[e * n_light + l]);
            grad[e * n_light + l] += one_minus_m * d_sig as f64 / sum * g;
            column_b[e] += g * sig as f64 / sum;
        }
    }

    // Step 2: the dense column-normalisation part −(1 − m)·σ'/S·B_e over touched columns.
    for &e in &touched {
        let e = e as usize;
        let b = column_b[e];
        if b == 0.0 {
            continue;
        }
        let factor = one_minus_m * b / column_sum[e];
        let th = &theta[e * n_light..(e + 1) * n_light];
        let gr = &mut grad[e * n_light..(e + 1) * n_light];
        for (g, &t) in gr.iter_mut().zip(th) {
            *g -= factor * sigmoid_and_derivative(t).1 as f64;
        }
    }
    (loss, skipped)
}
