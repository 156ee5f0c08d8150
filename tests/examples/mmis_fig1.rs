//! Analogues of the two canonical experiments of Fig. 1 of "Marginal Multiple Importance
//! Sampling" (West, Georgiev, Hachisuka 2022), built on `ember_core::mmis`.
//!
//! ```text
//! cargo run --release -p ember-tests --example mmis_fig1 -- [plot.svg] [trials]
//! ```
//!
//! The paper does not give its integrands; these are documented in `docs/mmis.md`. All
//! densities live on x ∈ [0, 1]; `tri(x; c, h)` is the triangle density on [c − h, c + h]
//! and `bump(x; c, w)` the raised cosine of half-width w, both integrating to one.
//!
//! (a) f(x) = ½ tri(x; 0.25, 0.2) + ½ bump(x; 0.72, 0.2), I = 1. Classical technique A:
//!     0.85 tri(x; 0.25, 0.22) + 0.15 (good on the left). Marginal technique B:
//!     t ~ tri(0.72, 0.15), x | t ~ 0.85 tri(x; t, 0.08) + 0.15 (good on the right; its
//!     marginal is a convolution, treated as intractable). N = 64 samples each for A
//!     alone, SMIS with B alone (64 pairs), MMIS with 32 + 32, and MIS with B's exact
//!     marginal (by quadrature), 32 + 32.
//! (b) f(x) = 0.1 + 0.3 Σ_k bump(x; c_k, 0.1), c = (0.2, 0.5, 0.8), I = 1. Marginal
//!     techniques k = 1..3: t ~ tri(c_k, 0.06), x | t ~ tri(x; t, 0.05), each covering only
//!     [c_k − 0.11, c_k + 0.11]; technique 4 (defensive): t ~ U[0, 1), x | t ~
//!     ½ + ½ wtri(x; t, ½) (wtri: the triangle wrapped around [0, 1)), whose marginal is
//!     uniform. Budget N = 64: MMIS_n draws n pairs per
//!     technique and averages N/(4n) realisations; MIS draws 16 per technique and
//!     evaluates the exact marginals (piecewise Gauss–Legendre over t, split at every kink
//!     of the integrand, hence exact to rounding).
//!
//! Prints the variance table and writes a log-log SVG plot (by hand). Exits with status 1
//! if the excess variance of MMIS_n over MIS does not shrink as n grows.

use ember_core::mmis::{Mmis, Technique};
use ember_core::rng::{SampleStream, Stream};
use ember_tests::mmis_1d::{Tech, bump, tri_pdf as tri};
use std::fmt::Write as _;

/// A technique presented to MMIS with its exact marginal: the reference MIS of eq. (1).
#[derive(Debug)]
struct Exact(Tech);

impl Technique<f64, f64> for Exact {
    fn pdf(&self, x: &f64, _: &f64) -> f64 {
        self.0.marginal(*x)
    }
    fn is_classical(&self) -> bool {
        true
    }
}

/// Mean, variance and the standard error of the variance of `trials` estimates.
struct Stats {
    mean: f64,
    se_mean: f64,
    var: f64,
    se_var: f64,
}

/// Run `trials` estimates, each averaging `realisations` MMIS estimates of `f` with
/// `counts[i]` pairs drawn from `samplers[i]` and weighed by `techs[i]`.
fn run(seed: u64, trials: u32, techs: &[&dyn Technique<f64, f64>], samplers: &[Tech], counts: &[usize], realisations: usize, f: fn(f64) -> f64) -> Stats {
    let mut buf = Vec::with_capacity(counts.iter().sum());
    let estimates: Vec<f64> = (0..trials)
        .map(|trial| {
            let mut rng = SampleStream::for_sample(seed, Stream::Aux, trial, 0, 0);
            let mut total = 0.0;
            for _ in 0..realisations {
                buf.clear();
                for (s, &n) in samplers.iter().zip(counts) {
                    buf.extend((0..n).map(|_| s.draw(&mut rng)));
                }
                total += Mmis::new(techs, counts, &buf).expect("consistent counts").estimate(|x| f(*x));
            }
            total / realisations as f64
        })
        .collect();
    let k = trials as f64;
    let mean = estimates.iter().sum::<f64>() / k;
    let m2 = estimates.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / k;
    let m4 = estimates.iter().map(|e| (e - mean).powi(4)).sum::<f64>() / k;
    let var = m2 * k / (k - 1.0);
    Stats { mean, se_mean: (var / k).sqrt(), var, se_var: ((m4 - m2 * m2) / k).sqrt() }
}

fn f_a(x: f64) -> f64 {
    0.5 * tri(x, 0.25, 0.2) + 0.5 * bump(x, 0.72, 0.2)
}

fn f_b(x: f64) -> f64 {
    0.1 + 0.3 * (bump(x, 0.2, 0.1) + bump(x, 0.5, 0.1) + bump(x, 0.8, 0.1))
}

const A: Tech = Tech::Classical { c: 0.25, h: 0.22, eps: 0.15 };
const B: Tech = Tech::Marginal { c: 0.72, w: 0.15, h: 0.08, eps: 0.15 };
const PARTS: [Tech; 4] = [
    Tech::Marginal { c: 0.2, w: 0.06, h: 0.05, eps: 0.0 },
    Tech::Marginal { c: 0.5, w: 0.06, h: 0.05, eps: 0.0 },
    Tech::Marginal { c: 0.8, w: 0.06, h: 0.05, eps: 0.0 },
    Tech::Wrapped,
];
/// One estimator of panel (a): name, plot label, techniques (as MMIS sees them), samplers, counts.
type Case<'a> = (&'a str, &'a str, Vec<&'a dyn Technique<f64, f64>>, Vec<Tech>, Vec<usize>);

const N: usize = 64;
const NS: [usize; 5] = [1, 2, 4, 8, 16];

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let out = args.get(1).map_or_else(|| std::env::temp_dir().join("mmis_fig1.svg"), Into::into);
    let trials: u32 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(50_000);

    // Check the quadrature: every marginal integrates to one.
    for (i, t) in PARTS.iter().chain([&B]).enumerate() {
        let cells = 20_000;
        let mass: f64 = (0..cells).map(|k| t.marginal((k as f64 + 0.5) / cells as f64)).sum::<f64>() / cells as f64;
        assert!((mass - 1.0).abs() < 1e-6, "marginal {i} integrates to {mass}");
    }

    println!("MMIS Fig. 1 analogues, N = {N} samples per estimate, {trials} estimates each (I = 1)\n");
    let mut rows_a = Vec::new();
    let exact_b = Exact(B);
    let cases: [Case; 4] = [
        ("classical A only", "A only", vec![&A], vec![A], vec![N]),
        ("SMIS, marginal B only", "SMIS, B only", vec![&B], vec![B], vec![N]),
        ("MMIS, A + B", "MMIS, A + B", vec![&A, &B], vec![A, B], vec![N / 2, N / 2]),
        ("MIS, A + exact marginal of B", "MIS, exact B", vec![&A, &exact_b], vec![A, B], vec![N / 2, N / 2]),
    ];
    println!("(a) classical + marginal\n");
    println!("| estimator | samples | mean | variance |");
    println!("|---|---|---|---|");
    for (seed, (name, label, techs, samplers, counts)) in cases.iter().enumerate() {
        let s = run(100 + seed as u64, trials, techs, samplers, counts, 1, f_a);
        let split = counts.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(" + ");
        println!("| {name} | {split} | {:.4} ± {:.4} | {:.3e} ± {:.1e} |", s.mean, s.se_mean, s.var, s.se_var);
        rows_a.push((*label, s.var));
    }

    println!("\n(b) three partial marginal techniques + a defensive one, T = 4\n");
    println!("| estimator | realisations × pairs | pdf evaluations | mean | variance | excess over MIS |");
    println!("|---|---|---|---|---|---|");
    let exact: Vec<Exact> = PARTS.iter().map(|&t| Exact(t)).collect();
    let exact_refs: Vec<&dyn Technique<f64, f64>> = exact.iter().map(|e| e as _).collect();
    let reference = run(200, trials, &exact_refs, &PARTS, &[N / 4; 4], 1, f_b);
    let parts: Vec<&dyn Technique<f64, f64>> = PARTS.iter().map(|t| t as _).collect();
    let mut rows_b = Vec::new();
    for (seed, &n) in NS.iter().enumerate() {
        let s = run(300 + seed as u64, trials, &parts, &PARTS, &[n; 4], N / (4 * n), f_b);
        let excess = s.var - reference.var;
        let se_excess = s.se_var.hypot(reference.se_var);
        println!(
            "| MMIS_{n} | {} × {} | {} | {:.4} ± {:.4} | {:.3e} ± {:.1e} | {excess:.3e} ± {se_excess:.1e} |",
            N / (4 * n),
            4 * n,
            n * N * 4,
            s.mean,
            s.se_mean,
            s.var,
            s.se_var
        );
        rows_b.push((n, s.var, excess));
    }
    println!(
        "| MIS, exact marginals | 1 × {N} | {} (+ quadrature) | {:.4} ± {:.4} | {:.3e} ± {:.1e} | 0 |",
        N * 4,
        reference.mean,
        reference.se_mean,
        reference.var,
        reference.se_var
    );

    std::fs::write(&out, svg(&rows_a, &rows_b, reference.var)).expect("write the plot");
    println!("\nplot: {}", out.display());
    let shrinks = rows_b.windows(2).all(|w| w[1].2 < w[0].2);
    println!("excess variance shrinks with n: {}", if shrinks { "yes" } else { "NO" });
    if !shrinks {
        std::process::exit(1);
    }
}

/// A two-panel plot with logarithmic axes: (a) variance per estimator; (b) variance and
/// excess variance of MMIS_n against n, with the exact-marginal MIS as a dashed line.
fn svg(rows_a: &[(&str, f64)], rows_b: &[(usize, f64, f64)], reference: f64) -> String {
    let (w, h, top, bottom, left) = (460.0, 360.0, 40.0, 300.0, 70.0);
    let right = w - 20.0;
    let mut s = String::new();
    let _ = writeln!(s, r#"<svg xmlns="http://www.w3.org/2000/svg" width="{}" height="{h}" font-family="sans-serif" font-size="11">"#, 2.0 * w);
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    // Decade range covering every plotted value.
    let values = rows_a.iter().map(|r| r.1).chain(rows_b.iter().flat_map(|r| [r.1, r.2])).chain([reference]);
    let logs: Vec<f64> = values.filter(|v| *v > 0.0).map(f64::log10).collect();
    let lo = logs.iter().copied().fold(f64::INFINITY, f64::min).floor();
    let hi = (logs.iter().copied().fold(f64::NEG_INFINITY, f64::max) + 0.1).ceil();
    let y = |v: f64| bottom - (v.log10() - lo) / (hi - lo) * (bottom - top);
    for (panel, title, xlabel) in
        [(0.0, "(a) classical + marginal, N = 64", ""), (w, "(b) MMIS_n vs MIS with exact marginals, N = 64", "n (pairs per technique)")]
    {
        let _ = writeln!(s, r#"<text x="{}" y="22" font-size="13">{title}</text>"#, panel + left);
        let _ = writeln!(s, r#"<rect x="{}" y="{top}" width="{}" height="{}" fill="none" stroke="black"/>"#, panel + left, right - left, bottom - top);
        for d in lo as i32..=hi as i32 {
            let yy = y(10f64.powi(d));
            let _ = writeln!(
                s,
                r##"<line x1="{}" x2="{}" y1="{yy}" y2="{yy}" stroke="#ddd"/><text x="{}" y="{}" text-anchor="end">1e{d}</text>"##,
                panel + left,
                panel + right,
                panel + left - 5.0,
                yy + 4.0
            );
        }
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" transform="rotate(-90 {} {})" text-anchor="middle">variance</text>"#,
            panel + 16.0,
            (top + bottom) / 2.0,
            panel + 16.0,
            (top + bottom) / 2.0
        );
        let _ = writeln!(s, r#"<text x="{}" y="{}" text-anchor="middle">{xlabel}</text>"#, panel + (left + right) / 2.0, bottom + 45.0);
    }
    // (a): one bar per estimator, from the bottom of the log axis.
    let slot = (right - left) / rows_a.len() as f64;
    for (i, (name, var)) in rows_a.iter().enumerate() {
        let x0 = left + slot * (i as f64 + 0.2);
        let _ = writeln!(s, r##"<rect x="{x0}" y="{}" width="{}" height="{}" fill="#4477aa"/>"##, y(*var), slot * 0.6, bottom - y(*var));
        let _ = writeln!(s, r#"<text x="{}" y="{}" text-anchor="middle" font-size="9">{}</text>"#, x0 + slot * 0.3, bottom + 14.0, name);
    }
    // (b): log2 axis in n.
    let nmax = rows_b.last().map_or(16.0, |r| r.0 as f64);
    let x = |n: f64| w + left + 20.0 + n.log2() / nmax.log2() * (right - left - 40.0);
    for &(n, ..) in rows_b {
        let _ = writeln!(s, r#"<text x="{}" y="{}" text-anchor="middle">{n}</text>"#, x(n as f64), bottom + 16.0);
    }
    let _ = writeln!(s, r##"<line x1="{}" x2="{}" y1="{2}" y2="{2}" stroke="#222" stroke-dasharray="6 4"/>"##, w + left, w + right, y(reference));
    for (k, color, label) in [(1usize, "#4477aa", "MMIS_n variance"), (2, "#cc6677", "excess over MIS")] {
        let pts: Vec<(f64, f64)> = rows_b.iter().map(|r| (r.0 as f64, if k == 1 { r.1 } else { r.2 })).filter(|p| p.1 > 0.0).collect();
        let line: Vec<String> = pts.iter().map(|&(n, v)| format!("{:.1},{:.1}", x(n), y(v))).collect();
        let _ = writeln!(s, r#"<polyline points="{}" fill="none" stroke="{color}" stroke-width="2"/>"#, line.join(" "));
        for &(n, v) in &pts {
            let _ = writeln!(s, r#"<circle cx="{:.1}" cy="{:.1}" r="3.5" fill="{color}"/>"#, x(n), y(v));
        }
        let ly = top + 16.0 * k as f64;
        let _ = writeln!(
            s,
            r#"<line x1="{}" x2="{}" y1="{ly}" y2="{ly}" stroke="{color}" stroke-width="2"/><text x="{}" y="{}">{label}</text>"#,
            w + right - 150.0,
            w + right - 130.0,
            w + right - 125.0,
            ly + 4.0
        );
    }
    let ly = top + 48.0;
    let _ = writeln!(
        s,
        r##"<line x1="{}" x2="{}" y1="{ly}" y2="{ly}" stroke="#222" stroke-dasharray="6 4"/><text x="{}" y="{}">MIS, exact marginals</text>"##,
        w + right - 150.0,
        w + right - 130.0,
        w + right - 125.0,
        ly + 4.0
    );
    s.push_str("</svg>\n");
    s
}
