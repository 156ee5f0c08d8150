//! The product-of-sums denominator of marginal path sampling (`ember_core::mmis`,
//! [MMIS eq. 14]): `Π_k Σ_j p_k(x_k | y_kj)` must equal the explicit sum over all tuples
//! of conditioning choices `Σ_(j_1..j_k) Π_k p_k(x_k | y_k,j_k)`, also beyond f64's range,
//! and the balance weights of all tuples must sum to one. Deterministic (no statistics).

use ember_core::mmis::{Scaled, product_of_sums, tuple_weight};
use ember_core::rng::{SampleStream, Stream};

/// Per-kernel candidate densities p_k(x_k | y_kj), log-uniform over 10^±spread.
fn kernels(rng: &mut SampleStream, k: usize, spread: f64, centre: f64) -> Vec<Vec<f64>> {
    (0..k)
        .map(|_| {
            let n = 1 + rng.next_below(4) as usize;
            (0..n).map(|_| 10f64.powf(centre + spread * (2.0 * rng.next_f64() - 1.0))).collect()
        })
        .collect()
}

/// Every tuple (j_1, …, j_k) of candidate indices, by a mixed-radix counter.
fn for_each_tuple(kernels: &[Vec<f64>], mut visit: impl FnMut(&[usize])) {
    let mut idx = vec![0usize; kernels.len()];
    loop {
        visit(&idx);
        let mut k = 0;
        loop {
            if k == kernels.len() {
                return;
            }
            idx[k] += 1;
            if idx[k] < kernels[k].len() {
                break;
            }
            idx[k] = 0;
            k += 1;
        }
    }
}

#[test]
fn product_of_sums_equals_brute_force_sum_over_tuples() {
    for trial in 0..300 {
        let mut rng = SampleStream::for_sample(41, Stream::Aux, trial, 0, 0);
        let ks = kernels(&mut rng, 1 + trial as usize % 6, 6.0, 0.0);
        let fast = product_of_sums(ks.iter().map(|k| k.iter().copied()));
        let (mut brute, mut weight_sum) = (0.0f64, 0.0f64);
        for_each_tuple(&ks, |idx| {
            let chosen = || idx.iter().zip(&ks).map(|(&j, k)| k[j]);
            brute += chosen().product::<f64>();
            weight_sum += tuple_weight(chosen(), fast);
        });
        let rel = (fast.to_f64() - brute).abs() / brute;
        assert!(rel < 1e-12, "trial {trial}: {} vs {brute} (rel {rel:e})", fast.to_f64());
        assert!((weight_sum - 1.0).abs() < 1e-12, "trial {trial}: tuple weights sum to {weight_sum}");
    }
}

/// Twelve vertices with densities near 1e35: products far beyond f64, compared with a
/// log-sum-exp brute force over the tuples.
#[test]
fn product_of_sums_stays_finite_beyond_f64() {
    for trial in 0..20 {
        let mut rng = SampleStream::for_sample(42, Stream::Aux, trial, 0, 0);
        let ks = kernels(&mut rng, 12, 5.0, if trial % 2 == 0 { 35.0 } else { -35.0 });
        let fast = product_of_sums(ks.iter().map(|k| k.iter().copied()));
        let mut logs = Vec::new();
        for_each_tuple(&ks, |idx| logs.push(idx.iter().zip(&ks).map(|(&j, k)| k[j].ln()).sum::<f64>()));
        let max = logs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let brute = max + logs.iter().map(|l| (l - max).exp()).sum::<f64>().ln();
        assert!(fast.to_f64() == 0.0 || fast.to_f64().is_infinite(), "the test must leave f64's range");
        assert!((fast.ln() - brute).abs() < 1e-12 * brute.abs(), "trial {trial}: {} vs {brute}", fast.ln());
        // The weights of the tuples still sum to one.
        let mut weight_sum = 0.0;
        for_each_tuple(&ks, |idx| weight_sum += tuple_weight(idx.iter().zip(&ks).map(|(&j, k)| k[j]), fast));
        assert!((weight_sum - 1.0).abs() < 1e-12, "trial {trial}: {weight_sum}");
    }
}

#[test]
fn a_kernel_without_positive_density_zeroes_the_product() {
    let ks = [vec![1.0, 2.0], vec![0.0, f64::NAN], vec![3.0]];
    let d = product_of_sums(ks.iter().map(|k| k.iter().copied()));
    assert!(d.is_zero());
    assert_eq!(d.divide(1.0), 0.0);
    assert_eq!(tuple_weight([1.0, 0.0, 3.0], d), 0.0);
    assert_eq!(product_of_sums(std::iter::empty::<[f64; 0]>()), Scaled::ONE);
}
