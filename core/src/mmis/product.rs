//! Product-of-sums denominators for path densities that factor per vertex
//! [MMIS eq. 13, 14].
//!
//! In multi-vertex filtering (and its adjoint, photon filtering; and recursive segment
//! MMIS) a conditional technique picks, independently at each of k filtered vertices,
//! one conditioning prefix `y` among the `N_k` candidates inside that vertex's kernel,
//! and its conditional path density factors per vertex:
//! `p(x̄ | ȳ) = Π_k p_k(x_k | y_k)`. The techniques are then all tuples
//! `(j_1, …, j_k)`, `T = Π_k N_k` of them with one pair each, and the MMIS denominator
//! of eq. (13), written out per vertex in eq. (14), distributes:
//!
//! ```text
//!   Σ_{(j_1..j_k)} Π_k p_k(x_k | y_{k,j_k})  =  Π_k Σ_j p_k(x_k | y_{k,j})
//! ```
//!
//! which costs `Σ_k N_k` density evaluations instead of `Π_k N_k`. The balance weight of
//! one tuple is the product of per-kernel weights `p_k(x_k | y_{k,j_k}) / Σ_j p_k(x_k | y_{k,j})`:
//! local MIS at each kernel, multiplied along the path ([`tuple_weight`]).
//!
//! A classical technique among the candidates (the path's own natural suffix, drawn
//! `n` times) enters its kernel's sum as the single term `n · p_k(x_k)`. Products of
//! many densities leave f64's range quickly (twenty vertices at 1e30 each), so the
//! results are [`Scaled`].

use super::Scaled;

/// `Π_k Σ_j p_k(x_k | y_{k,j})` (eq. 14 regrouped): one inner iterator of conditional
/// densities per filtered vertex. Terms that are not finite and positive are skipped; a
/// kernel whose sum is zero makes the whole denominator zero (no tuple reaches x̄), and
/// the caller must then skip the sample ([`Scaled::divide`] returns zero for it).
pub fn product_of_sums<K, J>(kernels: K) -> Scaled
where
    K: IntoIterator<Item = J>,
    J: IntoIterator<Item = f64>,
{
    Scaled::product(kernels.into_iter().map(Scaled::sum))
}

/// Balance weight of one tuple of conditioning choices: `Π_k chosen_k / denominator`,
/// where `chosen_k = p_k(x_k | y_{k,j_k})` and `denominator` is [`product_of_sums`]
/// over the same kernels. The weights of all tuples sum to one. Zero when the
/// denominator is zero.
pub fn tuple_weight(chosen: impl IntoIterator<Item = f64>, denominator: Scaled) -> f64 {
    Scaled::product(chosen.into_iter().map(Scaled::new)).ratio(denominator)
}
