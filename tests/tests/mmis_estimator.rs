//! Marginal MIS (`ember_core::mmis`): unbiasedness of eq. (6) on 1-D integrands with
//! known integrals, the special cases that must equal classical MIS and stochastic MIS
//! bit for bit, and numerical robustness. The product-of-sums denominator of eq. (14) is
//! tested in `mmis_product.rs`.
//!
//! Statistical tests: each runs 20 000 independent estimates with fixed seeds and a
//! two-sided z-test of their mean against the integral, Šidák-corrected over the
//! `UNBIASED_TESTS` z-tests in this file. Injected-bug checks (each done once, reverted),
//! in `core/src/mmis/estimator.rs`, `group_sum`:
//! - bug A, "n_i omitted from the denominator": each technique's term was its marginal
//!   density estimate instead of n_i times it (classical `p_i(x)` instead of
//!   `n_i p_i(x)`; marginal `(1/n_i) Σ_j p_i(x | t_ij)`, eq. 5's bracket, instead of the
//!   sum). Every unbiasedness test failed (z quoted at each test).
//! - bug B, "marginal treated as classical": the marginal branch returned
//!   `n_i · p_i(x | t_i1)` (one conditional technique for all pairs) instead of the sum
//!   over its pairs. Failed every test that has a marginal technique (z quoted).

use ember_core::mmis::{Mmis, Pair, Technique};
use ember_core::rng::{SampleStream, Stream};
use ember_tests::chi2::sidak;
use ember_tests::mmis_1d::{Tech, bump, tri_pdf};
use ember_tests::stats::{MeanVar, normal_two_sided_p};
use std::f64::consts::PI;

// ---------------------------------------------------------------------------------------
// Techniques and integrands (the 1-D family lives in `ember_tests::mmis_1d`).

const LEFT: Tech = Tech::Classical { c: 0.25, h: 0.22, eps: 0.15 };
const RIGHT_CLASSICAL: Tech = Tech::Classical { c: 0.72, h: 0.2, eps: 0.3 };
const RIGHT_MARGINAL: Tech = Tech::Marginal { c: 0.72, w: 0.15, h: 0.08, eps: 0.0 };
const WIDE_MARGINAL: Tech = Tech::Marginal { c: 0.5, w: 0.3, h: 0.2, eps: 0.1 };
const PARTIAL: [Tech; 4] = [
    Tech::Marginal { c: 0.2, w: 0.06, h: 0.05, eps: 0.0 },
    Tech::Marginal { c: 0.5, w: 0.06, h: 0.05, eps: 0.0 },
    Tech::Marginal { c: 0.8, w: 0.06, h: 0.05, eps: 0.0 },
    Tech::Wrapped,
];

/// Integrands with known integrals.
fn two_bumps(x: f64) -> f64 {
    0.5 * tri_pdf(x, 0.25, 0.2) + 0.5 * bump(x, 0.72, 0.2) // ∫ = 1
}
fn three_bumps(x: f64) -> f64 {
    0.1 + 0.3 * (bump(x, 0.2, 0.1) + bump(x, 0.5, 0.1) + bump(x, 0.8, 0.1)) // ∫ = 1
}
fn signed(x: f64) -> f64 {
    (2.0 * PI * x).sin() + x // ∫ = 1/2
}
fn square(x: f64) -> f64 {
    3.0 * x * x // ∫ = 1
}

/// Draw `counts[i]` pairs from each technique into `buf`, grouped by technique.
fn draw_all<'b>(techs: &[Tech], counts: &[usize], rng: &mut SampleStream, buf: &'b mut [Pair<f64, f64>]) -> &'b [Pair<f64, f64>] {
    let mut k = 0;
    for (tech, &n) in techs.iter().zip(counts) {
        for _ in 0..n {
            buf[k] = tech.draw(rng);
            k += 1;
        }
    }
    &buf[..k]
}

// ---------------------------------------------------------------------------------------
// Unbiasedness.

const UNBIASED_TESTS: usize = 6;
const TRIALS: u32 = 20_000;

fn check_unbiased(name: &str, seed: u64, techs: &[Tech], counts: &[usize], f: fn(f64) -> f64, integral: f64) {
    let mut stats = MeanVar::default();
    let mut buf = [Pair::default(); 16];
    for trial in 0..TRIALS {
        let mut rng = SampleStream::for_sample(seed, Stream::Aux, trial, 0, 0);
        let pairs = draw_all(techs, counts, &mut rng, &mut buf);
        let mmis = Mmis::new(techs, counts, pairs).expect("consistent counts");
        let estimate = mmis.estimate(|x| f(*x));
        assert!(estimate.is_finite(), "{name}: non-finite estimate {estimate}");
        stats.push(estimate);
    }
    let z = (stats.mean() - integral) / stats.std_error();
    let p = normal_two_sided_p(z);
    let alpha = sidak(0.01, UNBIASED_TESTS);
    println!("{name}: mean {:.5} ± {:.5} (I = {integral}), sd {:.4}, z = {z:.2}, p = {p:.3}", stats.mean(), stats.std_error(), stats.variance().sqrt());
    assert!(p >= alpha, "{name}: mean {} vs {integral}, z = {z:.2}, p = {p:.2e} < {alpha:.2e}", stats.mean());
}

/// Fig. 1 (top) analogue: a classical technique on the left bump, a marginal one that
/// covers only the right half. Bug A: z = 140.8; bug B: z = 100.1.
#[test]
fn unbiased_classical_plus_marginal() {
    check_unbiased("classical+marginal", 11, &[LEFT, RIGHT_MARGINAL], &[3, 2], two_bumps, 1.0);
}

/// T = 1: stochastic MIS. Bug A: z = 65.0; bug B: z = 91.7.
#[test]
fn unbiased_single_marginal_is_smis() {
    check_unbiased("single marginal (SMIS)", 12, &[WIDE_MARGINAL], &[4], square, 1.0);
}

/// All classical: the multi-sample balance heuristic. Bug A: z = 533.4 (bug B: no effect).
#[test]
fn unbiased_all_classical() {
    check_unbiased("all classical", 13, &[LEFT, RIGHT_CLASSICAL], &[3, 2], two_bumps, 1.0);
}

/// Fig. 1 (bottom) analogue: three partial marginal techniques plus a defensive one.
/// Bug A: z = 234.3; bug B: z = 116.7.
#[test]
fn unbiased_partial_marginals_with_defensive() {
    check_unbiased("partial marginals + defensive", 14, &PARTIAL, &[2, 2, 2, 2], three_bumps, 1.0);
}

/// A signed integrand with unequal counts. Bug A: z = 26.3; bug B: z = 47.1.
#[test]
fn unbiased_signed_integrand() {
    check_unbiased("signed integrand", 15, &PARTIAL, &[1, 3, 2, 1], signed, 0.5);
}

/// A technique drawn zero times (a subset of techniques, §3.1): the middle bump is then
/// reached only through the defensive technique. Bug A: z = 76.9; bug B: z = 86.0.
#[test]
fn unbiased_with_unused_technique() {
    check_unbiased("technique with n_i = 0", 16, &PARTIAL, &[2, 0, 2, 1], three_bumps, 1.0);
}

// ---------------------------------------------------------------------------------------
// Special cases, bit for bit.

/// T = 1 (stochastic MIS [West et al. 2020]): eq. (6) is `Σ_j f(x_j) / Σ_j' p(x_j | t_j')`.
#[test]
fn single_marginal_equals_stochastic_mis_bit_for_bit() {
    let mut buf = [Pair::default(); 16];
    for trial in 0..200 {
        let mut rng = SampleStream::for_sample(21, Stream::Aux, trial, 0, 0);
        let n = 1 + trial as usize % 7;
        let pairs = draw_all(&[WIDE_MARGINAL], &[n], &mut rng, &mut buf);
        let counts = [n];
        let mmis = Mmis::new(&[WIDE_MARGINAL], &counts, pairs).unwrap();
        let mut reference = 0.0;
        for sample in pairs {
            let mut d = 0.0;
            for other in pairs {
                d += WIDE_MARGINAL.pdf(&sample.x, &other.t);
            }
            reference += signed(sample.x) / d;
        }
        assert_eq!(mmis.estimate(|x| signed(*x)).to_bits(), reference.to_bits(), "trial {trial}");
    }
}

/// All classical: eq. (6) is eq. (4), `Σ_i Σ_j f(x_ij) / Σ_i' n_i' p_i'(x_ij)`, and agrees
/// with the unsimplified eq. (1) with balance weights (eq. 3) to rounding.
#[test]
fn all_classical_equals_multi_sample_balance_heuristic_bit_for_bit() {
    let techs = [LEFT, RIGHT_CLASSICAL, Tech::Classical { c: 0.5, h: 0.5, eps: 0.0 }];
    let mut buf = [Pair::default(); 16];
    for trial in 0..200 {
        let mut rng = SampleStream::for_sample(22, Stream::Aux, trial, 0, 0);
        let counts = [1 + trial as usize % 4, trial as usize % 3, 2];
        let pairs = draw_all(&techs, &counts, &mut rng, &mut buf);
        let mmis = Mmis::new(&techs, &counts, pairs).unwrap();
        let (mut eq4, mut eq1) = (0.0, 0.0);
        let mut k = 0;
        for (i, &n) in counts.iter().enumerate() {
            for _ in 0..n {
                let x = pairs[k].x;
                k += 1;
                let mut d = 0.0;
                for (q, &m) in techs.iter().zip(&counts) {
                    d += m as f64 * q.pdf(&x, &0.0);
                }
                eq4 += two_bumps(x) / d;
                let p = techs[i].pdf(&x, &0.0);
                let w = n as f64 * p / d;
                eq1 += w * two_bumps(x) / (n as f64 * p);
            }
        }
        let got = mmis.estimate(|x| two_bumps(*x));
        assert_eq!(got.to_bits(), eq4.to_bits(), "trial {trial}");
        assert!((got - eq1).abs() <= 1e-13 * eq1.abs(), "trial {trial}: {got} vs {eq1}");
    }
}

/// The classical shortcut (`n_i · p_i(x)`, one evaluation) equals summing the n_i equal
/// conditional terms of a technique declared marginal, to rounding.
#[test]
fn classical_shortcut_matches_marginal_treatment() {
    #[derive(Debug)]
    struct AsMarginal(Tech);
    impl Technique<f64, f64> for AsMarginal {
        fn pdf(&self, x: &f64, t: &f64) -> f64 {
            self.0.pdf(x, t)
        }
    }
    let classical: [&dyn Technique<f64, f64>; 2] = [&LEFT, &RIGHT_MARGINAL];
    let (as_marginal_left, right) = (AsMarginal(LEFT), RIGHT_MARGINAL);
    let marginal: [&dyn Technique<f64, f64>; 2] = [&as_marginal_left, &right];
    let mut buf = [Pair::default(); 16];
    for trial in 0..200 {
        let mut rng = SampleStream::for_sample(23, Stream::Aux, trial, 0, 0);
        let counts = [5, 3];
        let pairs = draw_all(&[LEFT, RIGHT_MARGINAL], &counts, &mut rng, &mut buf);
        let a = Mmis::new(&classical, &counts, pairs).unwrap().estimate(|x| two_bumps(*x));
        let b = Mmis::new(&marginal, &counts, pairs).unwrap().estimate(|x| two_bumps(*x));
        assert!((a - b).abs() <= 1e-14 * a.abs(), "trial {trial}: {a} vs {b}");
    }
}

// ---------------------------------------------------------------------------------------
// Robustness.

/// A technique whose conditional density is a fixed scale times a smooth positive shape
/// (or a fixed, possibly invalid, value).
#[derive(Clone, Copy, Debug)]
struct Fixed {
    scale: f64,
    classical: bool,
}

impl Technique<f64, f64> for Fixed {
    fn pdf(&self, x: &f64, t: &f64) -> f64 {
        self.scale * (1.5 + (3.0 * x + 5.0 * t).sin())
    }
    fn is_classical(&self) -> bool {
        self.classical
    }
}

/// Check finiteness and that the balance weights of `x` over all techniques sum to 1.
fn check_weights(name: &str, mmis: &Mmis<'_, Fixed, f64, f64>, x: f64) {
    let n = mmis.techniques().len();
    let weights: Vec<f64> = (0..n).map(|i| mmis.balance_weight(i, &x)).collect();
    let sum: f64 = weights.iter().sum();
    assert!(weights.iter().all(|w| w.is_finite() && (0.0..=1.0).contains(w)), "{name}: {weights:?}");
    assert!((sum - 1.0).abs() < 1e-12, "{name}: weights {weights:?} sum to {sum}");
    let c = mmis.contribution(&x, 1.0);
    assert!(c.is_finite() && c > 0.0, "{name}: contribution {c}");
}

#[test]
fn densities_spanning_sixty_orders_of_magnitude_give_finite_weights_summing_to_one() {
    let scales = [1e-30, 1e-20, 1e-10, 1.0, 1e10, 1e20, 1e30];
    let techs: Vec<Fixed> = scales.iter().enumerate().map(|(i, &scale)| Fixed { scale, classical: i % 2 == 0 }).collect();
    let counts = [2; 7];
    let pairs: Vec<Pair<f64, f64>> = (0..14).map(|k| Pair { t: 0.1 * k as f64, x: 0.05 * k as f64 }).collect();
    let mmis = Mmis::new(&techs, &counts, &pairs).unwrap();
    for pair in &pairs {
        check_weights("1e-30..1e30", &mmis, pair.x);
        // The 1e30 technique dominates (the next one is 1e10 times smaller).
        assert!(mmis.balance_weight(6, &pair.x) > 1.0 - 1e-9);
        assert!(mmis.balance_weight(0, &pair.x) > 0.0, "1e-30 technique must keep a positive weight");
    }
    assert!(mmis.estimate(|_| 1e-25).is_finite());

    // Beyond f64: 8 terms near 1e308 (the naive sum overflows) and 1e-300 ones.
    let huge = [Fixed { scale: 5e307, classical: false }, Fixed { scale: 1e-300, classical: true }];
    let counts = [8, 8];
    let pairs: Vec<Pair<f64, f64>> = (0..16).map(|k| Pair { t: 0.0, x: 0.1 * k as f64 }).collect();
    let mmis = Mmis::new(&huge, &counts, &pairs).unwrap();
    for pair in &pairs {
        check_weights("1e-300..1e308", &mmis, pair.x);
        assert!(mmis.denominator(&pair.x).to_f64().is_infinite(), "the test must exceed f64");
    }
}

#[test]
fn zero_and_invalid_densities_are_skipped_without_dividing_by_zero() {
    let techs = [
        Fixed { scale: 0.0, classical: false },
        Fixed { scale: f64::NAN, classical: false },
        Fixed { scale: -1.0, classical: true },
        Fixed { scale: f64::INFINITY, classical: false },
        Fixed { scale: 2.0, classical: false },
    ];
    let counts = [1, 1, 1, 1, 2];
    let pairs: Vec<Pair<f64, f64>> = (0..6).map(|k| Pair { t: 0.3 * k as f64, x: 0.17 * k as f64 }).collect();
    let mmis = Mmis::new(&techs, &counts, &pairs).unwrap();
    for pair in &pairs {
        check_weights("invalid densities", &mmis, pair.x);
        for i in 0..4 {
            assert_eq!(mmis.balance_weight(i, &pair.x), 0.0);
        }
    }
    // No technique reaches x: the contribution and the weights are zero, not NaN.
    let none = Mmis::new(&techs[..4], &counts[..4], &pairs[..4]).unwrap();
    assert_eq!(none.contribution(&0.5, 3.0), 0.0);
    assert_eq!(none.estimate(|_| 1.0), 0.0);
    assert!((0..4).all(|i| none.balance_weight(i, &0.5) == 0.0));
    // Inconsistent counts are refused, not trusted.
    assert!(Mmis::new(&techs, &[1, 1, 1, 1, 1], &pairs).is_none());
    assert!(Mmis::new(&techs[..2], &counts, &pairs).is_none());
    assert!(Mmis::new(&techs[..1], &[usize::MAX], &pairs).is_none());
}

/// The balance weights of a sample over the techniques sum to one wherever any drawn
/// technique reaches it, including points outside the partial techniques' supports.
#[test]
fn balance_weights_sum_to_one_on_random_configurations() {
    let mut buf = [Pair::default(); 16];
    for trial in 0..500 {
        let mut rng = SampleStream::for_sample(31, Stream::Aux, trial, 0, 0);
        let counts = [trial as usize % 3, 1 + trial as usize % 2, 2, 1 + (trial as usize / 3) % 3];
        let pairs = draw_all(&PARTIAL, &counts, &mut rng, &mut buf);
        let mmis = Mmis::new(&PARTIAL, &counts, pairs).unwrap();
        for k in 0..50 {
            let x = (k as f64 + 0.5) / 50.0;
            if mmis.denominator(&x).is_zero() {
                continue;
            }
            let sum: f64 = (0..4).map(|i| mmis.balance_weight(i, &x)).sum();
            assert!((sum - 1.0).abs() < 1e-12, "trial {trial}, x {x}: {sum}");
        }
    }
}
