//! Error against run time, as a record: the checkpoint schedule (√2 apart up to a
//! budget), one snapshot's error to a reference ([`Checkpoint`]), the reference with its
//! own noise floor from its two halves ([`Reference`]), seed averages, the time a curve
//! first reaches a target, and the CSV. Rendering to the checkpoints is the host's
//! (`ember-cli`'s `convergence`); the record is shared with any host that renders.

use std::fmt::Write as _;
use std::path::Path;

use ember_core::estimators::EstimatorKind;

use crate::image_io::{self, RgbImage};
use crate::metrics::{self, ErrorMetrics};

/// One snapshot.
#[derive(Clone, Copy, Debug)]
pub struct Checkpoint {
    pub estimator: EstimatorKind,
    pub seed: u32,
    pub target_seconds: f64,
    pub elapsed_seconds: f64,
    pub passes: u32,
    pub metrics: ErrorMetrics,
}

/// The reference and its noise floor.
#[derive(Clone, Debug)]
pub struct Reference {
    pub image: RgbImage,
    /// (relMSE, MAPE) of the reference's own noise, if its halves exist.
    pub floor: Option<(f64, f64)>,
}

impl Reference {
    /// Read `reference.exr`, and its halves `reference-half-{a,b}.exr` when present.
    pub fn load(path: &Path) -> Result<Self, String> {
        let image = image_io::read_exr(path).map_err(|e| e.to_string())?;
        let half = |s: &str| path.with_file_name(format!("reference-half-{s}.exr"));
        let floor = match (image_io::read_exr(&half("a")), image_io::read_exr(&half("b"))) {
            (Ok(a), Ok(b)) if a.pixels.len() == b.pixels.len() => {
                let m = metrics::compare(&a.pixels, &b.pixels);
                Some((m.rel_mse / 4.0, m.mape / 2.0))
            }
            _ => None,
        };
        Ok(Self { image, floor })
    }
}

/// Checkpoints 2^(k/2) s, k = 0, 1, 2, …, below the budget, then the budget itself.
pub fn checkpoints(budget: f64) -> Vec<f64> {
    let mut v = Vec::new();
    let mut k = 0;
    loop {
        let t = 2f64.powf(k as f64 / 2.0);
        if t >= budget * (1.0 - 1e-9) {
            break;
        }
        v.push(t);
        k += 1;
    }
    v.push(budget.max(f64::MIN_POSITIVE));
    v
}

/// The first time an error curve (seconds, error) reaches `target`, interpolated
/// log-log between the last checkpoint above and the first at or below it (errors of
/// unbiased estimators fall as a power of time, so the log-log segment is the natural
/// model); `None` when the curve never reaches it. A curve at or below the target from
/// its first checkpoint reports that checkpoint's time.
pub fn time_to_reach(curve: &[(f64, f64)], target: f64) -> Option<f64> {
    let i = curve.iter().position(|p| p.1 <= target)?;
    let (t1, e1) = curve[i];
    if i == 0 {
        return Some(t1);
    }
    let (t0, e0) = curve[i - 1];
    if !(e0 > 0.0 && e1 > 0.0 && t0 > 0.0 && t1 > t0) || e1 >= e0 {
        return Some(t1);
    }
    let f = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
    Some((t0.ln() + f.clamp(0.0, 1.0) * (t1.ln() - t0.ln())).exp())
}

/// Seed-averaged (elapsed seconds, relMSE, MAPE) per checkpoint of one estimator.
pub fn averaged(points: &[Checkpoint], estimator: EstimatorKind) -> Vec<(f64, f64, f64)> {
    let mut targets: Vec<f64> = points.iter().filter(|c| c.estimator == estimator).map(|c| c.target_seconds).collect();
    targets.dedup();
    targets
        .into_iter()
        .map(|t| {
            let at: Vec<&Checkpoint> = points.iter().filter(|c| c.estimator == estimator && c.target_seconds == t).collect();
            let n = at.len().max(1) as f64;
            (
                at.iter().map(|c| c.elapsed_seconds).sum::<f64>() / n,
                at.iter().map(|c| c.metrics.rel_mse).sum::<f64>() / n,
                at.iter().map(|c| c.metrics.mape).sum::<f64>() / n,
            )
        })
        .collect()
}

/// The CSV: one row per snapshot.
pub fn csv(points: &[Checkpoint]) -> String {
    let mut s = String::from("estimator,seed,checkpoint_s,elapsed_s,passes,relmse,mape,mae,mean_ratio\n");
    for c in points {
        let m = c.metrics;
        let _ = writeln!(
            s,
            "{},{},{},{:.4},{},{:.6e},{:.6},{:.6e},{:.6}",
            c.estimator.name(),
            c.seed,
            c.target_seconds,
            c.elapsed_seconds,
            c.passes,
            m.rel_mse,
            m.mape,
            m.mae,
            m.mean_ratio
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkpoints_grow_by_root_two_up_to_the_budget() {
        let c = checkpoints(4.0);
        assert_eq!(c.len(), 5);
        for (got, want) in c.iter().zip([1.0, 2f64.sqrt(), 2.0, 8f64.sqrt(), 4.0]) {
            assert!((got - want).abs() < 1e-12, "{c:?}");
        }
        assert_eq!(checkpoints(3.0).last(), Some(&3.0));
        assert_eq!(checkpoints(0.5), vec![0.5]);
    }

    #[test]
    fn time_to_reach_interpolates_a_power_law_exactly() {
        // error = 10 / t: reaches 3 at t = 10/3, between the checkpoints 2 and 4.
        let curve: Vec<(f64, f64)> = [1.0, 2.0, 4.0, 8.0].iter().map(|&t| (t, 10.0 / t)).collect();
        let t = time_to_reach(&curve, 3.0).unwrap();
        assert!((t - 10.0 / 3.0).abs() < 1e-9, "{t}");
        assert_eq!(time_to_reach(&curve, 20.0), Some(1.0));
        assert_eq!(time_to_reach(&curve, 1.0), None);
    }
}
