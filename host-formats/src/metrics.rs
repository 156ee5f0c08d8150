//! Image error metrics, exactly as `docs/algorithms.md` §5 of the shared notes defines
//! them (and as the SPCBPT paper's MAPE code computes it):
//!
//! - relMSE = mean over pixels and channels of (a − b)² / (b² + 0.01);
//! - MAPE = 100 · mean over pixels of clamp(mean over channels of |a − b| / (b + 0.01), 0, 10);
//! - MAE = mean over pixels and channels of |a − b|;
//! - ratio of means = mean(a) / mean(b).
//!
//! `a` is the image under test, `b` the reference. pbrt-v4's MRSE divides by (b + 0.01)²
//! instead; it is not used here. Sums are in f64.

/// The four numbers `ember compare` prints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorMetrics {
    pub rel_mse: f64,
    pub mape: f64,
    pub mae: f64,
    pub mean_ratio: f64,
    /// Share of the relative squared error (relMSE's sum) held by the 8 worst pixels:
    /// near 1 when a few fireflies dominate the error (per-block means can still agree).
    pub worst8_share: f64,
}

/// Pixels counted by [`ErrorMetrics::worst8_share`].
pub const WORST_PIXELS: usize = 8;

/// Metrics of `test` against `reference` (same size, checked by the caller).
pub fn compare(test: &[[f32; 3]], reference: &[[f32; 3]]) -> ErrorMetrics {
    assert_eq!(test.len(), reference.len(), "images must have the same size");
    let n = test.len().max(1) as f64;
    let (mut rel, mut ape, mut ae, mut sa, mut sb) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut worst = [0.0f64; WORST_PIXELS];
    for (a, b) in test.iter().zip(reference) {
        let mut pixel_ape = 0.0f64;
        let mut pixel_rel = 0.0f64;
        for c in 0..3 {
            let (a, b) = (a[c] as f64, b[c] as f64);
            let d = a - b;
            pixel_rel += d * d / (b * b + 0.01);
            pixel_ape += d.abs() / (b + 0.01);
            ae += d.abs();
            sa += a;
            sb += b;
        }
        ape += (pixel_ape / 3.0).clamp(0.0, 10.0);
        rel += pixel_rel;
        // Keep the largest few (sorted descending; NaN never enters).
        if pixel_rel > worst[WORST_PIXELS - 1] {
            worst[WORST_PIXELS - 1] = pixel_rel;
            worst.sort_by(|x, y| y.total_cmp(x));
        }
    }
    let worst8_share = if rel > 0.0 { worst.iter().sum::<f64>() / rel } else { 0.0 };
    ErrorMetrics { rel_mse: rel / (3.0 * n), mape: 100.0 * ape / n, mae: ae / (3.0 * n), mean_ratio: if sb != 0.0 { sa / sb } else { f64::NAN }, worst8_share }
}

/// Per-pixel relative error |a − b| / (b + 0.01) averaged over channels (MAPE's d),
/// for the false-colour image.
pub fn per_pixel_relative_error(test: &[[f32; 3]], reference: &[[f32; 3]]) -> Vec<f32> {
    test.iter().zip(reference).map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs() / (b[c] + 0.01)).sum::<f32>() / 3.0).collect()
}

/// False colour for a relative error: black (0) → blue → green → yellow → red (≥ `max`),
/// linear in log10 between max/1000 and max.
pub fn false_colour(err: f32, max: f32) -> [f32; 3] {
    if !(err > max * 1e-3) {
        return [0.0; 3];
    }
    let t = ((err / max).log10() / 3.0 + 1.0).clamp(0.0, 1.0);
    const STOPS: [[f32; 3]; 5] = [[0.0, 0.0, 0.2], [0.0, 0.2, 1.0], [0.0, 0.9, 0.2], [1.0, 0.9, 0.0], [1.0, 0.0, 0.0]];
    let x = t * (STOPS.len() - 1) as f32;
    let i = (x as usize).min(STOPS.len() - 2);
    let f = x - i as f32;
    [0, 1, 2].map(|c| STOPS[i][c] + f * (STOPS[i + 1][c] - STOPS[i][c]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_have_zero_error() {
        let img = vec![[0.5f32, 1.0, 2.0]; 16];
        let m = compare(&img, &img);
        assert_eq!((m.rel_mse, m.mape, m.mae), (0.0, 0.0, 0.0));
        assert_eq!(m.mean_ratio, 1.0);
    }

    #[test]
    fn hand_computed_values() {
        // One pixel: a = (1, 0, 3), b = (0.99, 0, 1).
        let a = [[1.0f32, 0.0, 3.0]];
        let b = [[0.99f32, 0.0, 1.0]];
        let m = compare(&a, &b);
        let rel = ((0.01f64 * 0.01) / (0.99f64 * 0.99 + 0.01) + 0.0 + 4.0 / 1.01) / 3.0;
        let ape = (0.01f64 / 1.0 + 0.0 + 2.0 / 1.01) / 3.0;
        assert!((m.rel_mse - rel).abs() < 1e-6, "{} vs {rel}", m.rel_mse);
        assert!((m.mape - 100.0 * ape).abs() < 1e-4, "{} vs {}", m.mape, 100.0 * ape);
        assert!((m.mae - (0.01 + 2.0) / 3.0).abs() < 1e-6);
        assert!((m.mean_ratio - 4.0 / 1.99).abs() < 1e-6);
    }

    #[test]
    fn worst_pixels_share_of_the_error() {
        let reference = vec![[1.0f32; 3]; 100];
        // Every pixel off by the same amount: the 8 worst hold 8 %.
        let even: Vec<[f32; 3]> = reference.iter().map(|_| [1.1f32; 3]).collect();
        assert!((compare(&even, &reference).worst8_share - 0.08).abs() < 1e-9);
        // One firefly among tiny errors holds nearly all of it.
        let mut firefly = reference.clone();
        firefly[37] = [50.0; 3];
        firefly[3] = [1.001; 3];
        let m = compare(&firefly, &reference);
        assert!(m.worst8_share > 0.999 && m.worst8_share <= 1.0, "{}", m.worst8_share);
        assert_eq!(compare(&reference, &reference).worst8_share, 0.0);
    }

    #[test]
    fn mape_clamps_each_pixel_at_ten() {
        let m = compare(&[[100.0f32; 3]], &[[0.0f32; 3]]);
        assert_eq!(m.mape, 1000.0);
    }
}
