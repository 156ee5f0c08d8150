//! One-dimensional densities and techniques for the marginal-MIS tests and the Fig. 1
//! example: triangles, raised-cosine bumps, and classical, marginal and defensive
//! techniques built from them on x ∈ [0, 1].

use ember_core::mmis::{Pair, Technique};
use ember_core::rng::SampleStream;
use std::f64::consts::PI;

/// Symmetric triangle density on [c − h, c + h].
pub fn tri_pdf(x: f64, c: f64, h: f64) -> f64 {
    ((h - (x - c).abs()) / (h * h)).max(0.0)
}

/// Inverse-CDF sample of `tri_pdf(·, c, h)`.
pub fn tri_sample(u: f64, c: f64, h: f64) -> f64 {
    if u < 0.5 { c - h + h * (2.0 * u).sqrt() } else { c + h - h * (2.0 * (1.0 - u)).sqrt() }
}

/// Raised-cosine bump of half-width w centred at c, integrating to one.
pub fn bump(x: f64, c: f64, w: f64) -> f64 {
    if (x - c).abs() < w { (1.0 + (PI * (x - c) / w).cos()) / (2.0 * w) } else { 0.0 }
}

/// The test techniques on x ∈ [0, 1] (supports chosen inside [0, 1]: no truncation).
#[derive(Clone, Copy, Debug)]
pub enum Tech {
    /// Classical: `(1 − eps)·tri(x; c, h) + eps` (uniform defensive part).
    Classical { c: f64, h: f64, eps: f64 },
    /// Marginal: `t ~ tri(c, w)`, then `x | t ~ (1 − eps)·tri(x; t, h) + eps`.
    /// With eps = 0 it covers only [c − w − h, c + w + h].
    Marginal { c: f64, w: f64, h: f64, eps: f64 },
    /// Marginal, defensive: `t ~ U[0, 1)`, then x uniform or (½ each) `x = frac(t + s)`
    /// with `s ~ tri(0, ½)`: the conditional is ½ + ½·(wrapped triangle) ≥ ½, the
    /// marginal uniform.
    Wrapped,
}

impl Technique<f64, f64> for Tech {
    fn pdf(&self, x: &f64, t: &f64) -> f64 {
        match *self {
            Tech::Classical { c, h, eps } => (1.0 - eps) * tri_pdf(*x, c, h) + eps,
            Tech::Marginal { h, eps, .. } => (1.0 - eps) * tri_pdf(*x, *t, h) + eps,
            Tech::Wrapped => {
                let d = (x - t).rem_euclid(1.0);
                0.5 + 0.5 * tri_pdf(d.min(1.0 - d), 0.0, 0.5)
            }
        }
    }
    fn is_classical(&self) -> bool {
        matches!(self, Tech::Classical { .. })
    }
}

impl Tech {
    /// One technique-sample pair (t, x); t = 0 for the classical technique.
    pub fn draw(&self, rng: &mut SampleStream) -> Pair<f64, f64> {
        let (u0, u1, u2) = (rng.next_f64(), rng.next_f64(), rng.next_f64());
        match *self {
            Tech::Classical { c, h, eps } => Pair { t: 0.0, x: if u0 < eps { u1 } else { tri_sample(u1, c, h) } },
            Tech::Marginal { c, w, h, eps } => {
                let t = tri_sample(u0, c, w);
                Pair { t, x: if u1 < eps { u2 } else { tri_sample(u2, t, h) } }
            }
            Tech::Wrapped => Pair { t: u0, x: if u1 < 0.5 { u2 } else { (u0 + tri_sample(u2, 0.0, 0.5)).rem_euclid(1.0) } },
        }
    }

    /// The marginal density `p(x) = ∫ p(x | t) p(t) dt`, by 5-point Gauss–Legendre on the
    /// pieces between the kinks in t (the integrand is piecewise quadratic there).
    pub fn marginal(&self, x: f64) -> f64 {
        const NODES: [f64; 5] = [0.0, -0.538_469_310_105_683_1, 0.538_469_310_105_683_1, -0.906_179_845_938_664, 0.906_179_845_938_664];
        const WEIGHTS: [f64; 5] = [0.568_888_888_888_888_9, 0.478_628_670_499_366_5, 0.478_628_670_499_366_5, 0.236_926_885_056_189_1, 0.236_926_885_056_189_1];
        let (lo, hi, kinks, pt): (f64, f64, [f64; 6], &dyn Fn(f64) -> f64) = match self {
            Tech::Classical { .. } => return self.pdf(&x, &0.0),
            Tech::Marginal { c, w, h, .. } => (c - w, c + w, [c - w, *c, c + w, x - h, x, x + h], &|t| tri_pdf(t, *c, *w)),
            Tech::Wrapped => (0.0, 1.0, [0.0, 1.0, x, (x + 0.5).rem_euclid(1.0), x, x], &|_| 1.0),
        };
        let mut cuts = kinks.map(|k| k.clamp(lo, hi));
        cuts.sort_by(f64::total_cmp);
        let mut sum = 0.0;
        for piece in cuts.windows(2) {
            let (a, b) = (piece[0], piece[1]);
            for (n, wt) in NODES.iter().zip(WEIGHTS) {
                let t = 0.5 * (a + b) + 0.5 * (b - a) * n;
                sum += 0.5 * (b - a) * wt * self.pdf(&x, &t) * pt(t);
            }
        }
        sum
    }
}
