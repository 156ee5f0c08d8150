//! Marginal multiple importance sampling (MMIS) [West, Georgiev and Hachisuka 2022,
//! "Marginal Multiple Importance Sampling", SIGGRAPH Asia; cited below as eq. (n)].
//!
//! # What it estimates
//!
//! `I = ∫ f(x) dx` from `T ≥ 1` sampling techniques, technique `i` drawing `n_i`
//! samples. Multi-sample MIS (eq. 1) with balance-heuristic weights (eq. 3) simplifies to
//! one term per sample (eq. 4):
//!
//! ```text
//!   ⟨I⟩_MIS = Σ_i Σ_j f(x_ij) / Σ_i' n_i' p_i'(x_ij)
//! ```
//!
//! A *marginal* technique first draws an auxiliary variable `t ~ p_i(t)` (a technique
//! identifier in its own technique space 𝒯_i: a prefix vertex, a kernel centre, a
//! wavelength) and then `x ~ p_i(x | t)`; its density is the marginal
//! `p_i(x) = ∫ p_i(x | t) p_i(t) dt` (eq. 2), generally intractable. MMIS replaces each
//! `n_i' p_i'(x)` in the denominator by the estimate built from the technique's own
//! `n_i'` technique-sample pairs `(t_i'j', x_i'j')` (eq. 5), which yields eq. (6):
//!
//! ```text
//!   ⟨I⟩_MMIS = Σ_i Σ_j f(x_ij) / Σ_i' Σ_j' p_i'(x_ij | t_i'j')
//! ```
//!
//! Only conditional densities are ever evaluated.
//!
//! # Why it is unbiased
//!
//! The denominator `D(x) = Σ_i' Σ_j' p_i'(x | t_i'j')` depends on the `t`s only, and
//! given them each `x_ij` is an independent draw from `p_i(· | t_ij)`. Hence
//! `E[⟨I⟩ | t] = ∫ f(x) Σ_ij p_i(x | t_ij) / D(x) dx = ∫_{D > 0} f(x) dx`: the estimate
//! is unbiased as long as, for every realisation of the `t`s, some drawn conditional
//! technique has positive density wherever `f ≠ 0` (§3.1). The caller may use any
//! (random) subset of techniques, including `n_i = 0`, under that condition.
//!
//! # Classical techniques, and the special cases
//!
//! A classical technique is a marginal one whose conditional density ignores `t`
//! (§3.1, "Combining classical and marginal techniques"): its `n_i` inner terms are
//! equal, so [`Mmis`] evaluates it once and multiplies by `n_i`
//! ([`Technique::is_classical`]). With only classical techniques eq. (6) *is* eq. (4),
//! the classical multi-sample balance heuristic, operation for operation; with `T = 1`
//! marginal technique it is stochastic MIS [West et al. 2020].
//!
//! The balance weight of technique `i` at `x` is
//! `w_i(x) = Σ_j p_i(x | t_ij) / D(x)` ([`Mmis::balance_weight`]; `n_i p_i(x) / D(x)`
//! when classical); the weights of one sample over all techniques sum to one, and
//! `w_i(x) f(x) / (Σ_j p_i(x | t_ij))` recovers the contribution of eq. (1).
//!
//! # Paths whose density factors per vertex
//!
//! Marginal path sampling (eq. 13) reads the same with paths `x̄` and auxiliary vertices
//! `t̄`. When techniques pick one conditioning vertex per filtered vertex independently,
//! the sum over the exponentially many tuples in eq. (14) regroups into a product of
//! per-vertex sums: [`product_of_sums`] and [`tuple_weight`] (module `product`).
//!
//! # Numerics and allocation
//!
//! Denominators are f64 sums held as [`Scaled`] (mantissa plus a power-of-two exponent),
//! so densities from 1e-300 to 1e300 can share one denominator and products of many
//! per-vertex densities stay finite; inside [1e-150, 1e150] the arithmetic is plain f64,
//! bit for bit. Densities that are zero, negative or not finite are skipped, and a zero
//! denominator gives a zero contribution, never a division by zero. Nothing here
//! allocates: techniques, counts and pairs are caller-provided slices, and the
//! per-vertex densities of eq. (14) arrive as iterators.

mod estimator;
mod product;
mod scaled;

pub use estimator::Mmis;
pub use product::{product_of_sums, tuple_weight};
pub use scaled::Scaled;

/// A sampling technique, known to MMIS through its conditional density `p_i(x | t)`
/// (eq. 2, 6), for the generic estimator [`Mmis`]. The paper's canonical experiments
/// (`tests/tests/mmis_estimator.rs`, `mmis_fig1`) and the fuzz targets implement it; the
/// path filters (`estimators::filter`) do not: their denominators are eq. (14)'s product
/// of sums regrouped per kernel and propagated over a graph of nodes in f32/f64 (one sweep
/// per depth), a shape that a per-sample trait call and [`Scaled`] arithmetic would only
/// slow down, so they keep their own and are checked against brute-force sums instead.
///
/// `X` is the sample space (a point, a path, a segment), `T` the auxiliary variable that
/// conditions sampling. Techniques with different technique spaces share one `T`
/// (typically a closed enum) and are combined through one implementing type (again a
/// closed enum), or through `&dyn Technique<X, T>` set up once per estimate.
pub trait Technique<X, T> {
    /// Conditional density `p_i(x | t)` of drawing `x` given the auxiliary variable `t`,
    /// in the measure of `X`. A classical technique ignores `t`. Return zero (not NaN)
    /// where `x` cannot be drawn; non-finite or negative values are treated as zero.
    fn pdf(&self, x: &X, t: &T) -> f64;

    /// Whether [`pdf`](Technique::pdf) ignores `t` (a classical technique): its `n_i`
    /// denominator terms are then evaluated once, as `n_i · p_i(x)`. Defaults to
    /// `false` (marginal), which is always correct, only slower.
    fn is_classical(&self) -> bool {
        false
    }
}

impl<X, T, Q: Technique<X, T> + ?Sized> Technique<X, T> for &Q {
    #[inline]
    fn pdf(&self, x: &X, t: &T) -> f64 {
        (**self).pdf(x, t)
    }
    #[inline]
    fn is_classical(&self) -> bool {
        (**self).is_classical()
    }
}

/// One technique-sample pair `(t_ij, x_ij)`: `t_ij ~ p_i(t)`, then `x_ij ~ p_i(x | t_ij)`
/// (§3.1). For a classical technique `t` is whatever value its `T` offers; it is ignored.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pair<X, T> {
    /// The auxiliary variable (conditional-technique identifier).
    pub t: T,
    /// The sample drawn conditionally on `t`.
    pub x: X,
}
