//! The MMIS estimator of eq. (6) over caller-provided techniques, sample counts and
//! technique-sample pairs, with its balance weights.

use super::{Pair, Scaled, Technique};

/// One MMIS combination: `T` techniques, their sample counts `n_i`, and the
/// `Σ_i n_i` technique-sample pairs, grouped by technique in order (the first `n_0`
/// pairs were drawn from technique 0, the next `n_1` from technique 1, …), as eq. (6)
/// indexes them by `(i, j)`. Borrowed, never copied; validated once by [`Mmis::new`].
///
/// Cost: one conditional-density evaluation per marginal pair and one per classical
/// technique for each denominator, so [`Mmis::estimate`] costs `O(N²)` evaluations for
/// `N` pairs (the `n·N·T` of §3.2 per `N/(nT)` realisations).
#[derive(Debug)]
pub struct Mmis<'a, Q, X, T> {
    techniques: &'a [Q],
    counts: &'a [usize],
    pairs: &'a [Pair<X, T>],
}

impl<Q, X, T> Clone for Mmis<'_, Q, X, T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<Q, X, T> Copy for Mmis<'_, Q, X, T> {}

impl<'a, Q, X, T> Mmis<'a, Q, X, T> {
    /// The combination of `techniques`, drawn `counts[i]` times each, with the pairs
    /// grouped by technique in order. `None` unless there is one count per technique and
    /// the counts add up to the number of pairs.
    pub fn new(techniques: &'a [Q], counts: &'a [usize], pairs: &'a [Pair<X, T>]) -> Option<Self> {
        let total = counts.iter().try_fold(0usize, |acc, &n| acc.checked_add(n))?;
        (counts.len() == techniques.len() && total == pairs.len()).then_some(Self { techniques, counts, pairs })
    }

    /// The techniques.
    pub fn techniques(&self) -> &'a [Q] {
        self.techniques
    }

    /// The sample counts `n_i`.
    pub fn counts(&self) -> &'a [usize] {
        self.counts
    }

    /// All pairs, grouped by technique.
    pub fn pairs(&self) -> &'a [Pair<X, T>] {
        self.pairs
    }

    /// Each technique with its `n_i` pairs, in order.
    pub fn groups(&self) -> impl Iterator<Item = (&'a Q, &'a [Pair<X, T>])> + use<'a, Q, X, T> {
        let mut rest = self.pairs;
        self.techniques.iter().zip(self.counts).map(move |(q, &n)| {
            // `new` guarantees the split exists; an empty group is the safe fallback.
            let (group, tail) = rest.split_at_checked(n).unwrap_or((rest, &[]));
            rest = tail;
            (q, group)
        })
    }
}

impl<Q: Technique<X, T>, X, T> Mmis<'_, Q, X, T> {
    /// Technique `q`'s share of the denominator at `x`: `Σ_j p_q(x | t_j)` over its
    /// pairs (eq. 5 times `n_i`), or `n_i · p_q(x)` when classical.
    fn group_sum(q: &Q, group: &[Pair<X, T>], x: &X) -> Scaled {
        match group.first() {
            None => Scaled::ZERO,
            Some(first) if q.is_classical() => Scaled::new(q.pdf(x, &first.t)).times(Scaled::new(group.len() as f64)),
            Some(_) => Scaled::sum(group.iter().map(|pair| q.pdf(x, &pair.t))),
        }
    }

    /// Technique `i`'s share of the denominator at `x` (zero for an unknown `i`).
    pub fn technique_sum(&self, i: usize, x: &X) -> Scaled {
        self.groups().nth(i).map_or(Scaled::ZERO, |(q, group)| Self::group_sum(q, group, x))
    }

    /// The MMIS denominator of eq. (6) at `x`: `D(x) = Σ_i' Σ_j' p_i'(x | t_i'j')`,
    /// summed technique by technique in order.
    pub fn denominator(&self, x: &X) -> Scaled {
        self.groups().fold(Scaled::ZERO, |d, (q, group)| d.plus(Self::group_sum(q, group, x)))
    }

    /// Balance weight of technique `i` at `x`: `Σ_j p_i(x | t_ij) / D(x)` (eq. 3 with
    /// the marginal replaced by its estimate, eq. 5). The weights over all techniques
    /// sum to one wherever `D(x) > 0`; all are zero where `D(x) = 0`.
    pub fn balance_weight(&self, i: usize, x: &X) -> f64 {
        self.technique_sum(i, x).ratio(self.denominator(x))
    }

    /// The MMIS contribution of one sample, `f(x) / D(x)` (eq. 6); zero where no drawn
    /// technique reaches `x`.
    pub fn contribution(&self, x: &X, f: f64) -> f64 {
        self.denominator(x).divide(f)
    }

    /// The MMIS estimate of eq. (6): the sum of [`Mmis::contribution`] over all pairs,
    /// in pair order. `f` is evaluated once per pair.
    pub fn estimate(&self, mut f: impl FnMut(&X) -> f64) -> f64 {
        self.pairs.iter().fold(0.0, |acc, pair| acc + self.contribution(&pair.x, f(&pair.x)))
    }
}
