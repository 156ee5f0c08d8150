//! Issue 18's diagnostic: what SPCBPT's Γ learned against the oracle Γ of a run.
//!
//!     cargo run --release -p ember-cli --example spcbpt_oracle -- SCENE W H PASSES OUT_DIR [STEPS [REUSE]]
//!
//! Trains SPCBPT with the default settings (STEPS: Adam steps at least, default the
//! core's; 0 gives the old fixed batch of 10 000; REUSE: M0, default the core's),
//! renders PASSES passes, and after each
//! pass sums every connection's unweighted value by (eye subspace, light subspace)
//! (`ember_core::estimators::spcbpt::oracle`). Prints the contribution-weighted
//! KL(oracle ‖ Γ), the same for a uniform Γ, and Γ's mass on light subspaces that gave
//! an eye subspace nothing; writes OUT_DIR/heatmap.png: Γ(l|e) left, the oracle right,
//! rows eye subspaces and columns light subspaces both ordered by the mean x of their
//! vertices (on ajar and door the wall is at x = 1; grey lines mark it), colour
//! log10(n_light · value) from −2 (blue) through 0 (white, uniform) to +2 (red), black
//! where the oracle is zero.
//!
//! Also printed: the spread of stage 2 (per non-empty light subspace, the effective
//! share 1 / (n Σ P_r²) of its n candidates under P_r ∝ f_y/p, and n · max P_r, averaged
//! with the subspace's total f_y/p as weight), and with REUSE = 0 a check of Q (eq. 19):
//! the passes' mean Σ f_y/p per subspace over M against the preprocessing's Q (totals
//! and the relative L1 distance Σ|Q̂ − Q| / ΣQ, which the passes' noise keeps above 0).

use std::path::PathBuf;
use std::time::Instant;

use ember_cli::cli::{CacheArgs, EstimatorKind};
use ember_cli::estimators::CoreRenderer;
use ember_cli::film::Film;
use ember_cli::progress::DriverConfig;
use ember_cli::setup::prepare_file;
use ember_core::estimators::Renderer;
use ember_core::estimators::spcbpt::oracle::{ConnectionSums, connection_sums, distance};
use ember_core::transport::RenderParams;
use ember_core::transport::{Heuristic, MaxDepth};
use ember_host::driver::Limits;
use rayon::prelude::*;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 5 {
        eprintln!("usage: spcbpt_oracle SCENE W H PASSES OUT_DIR [STEPS]");
        std::process::exit(2);
    }
    let (scene, out) = (PathBuf::from(&args[0]), PathBuf::from(&args[4]));
    let num = |i: usize| args[i].parse::<u32>().expect("a number");
    let (w, h, passes) = (num(1), num(2), num(3));
    let mut cache = CacheArgs::default();
    if args.len() > 5 {
        cache.steps = num(5);
    }
    if args.len() > 6 {
        cache.reuse = num(6);
    }
    std::fs::create_dir_all(&out).expect("output directory");
    let prepared = prepare_file(&scene, Some(w), Some(h), Vec::new()).expect("scene loads");
    let depth = prepared.max_depth.unwrap_or(-1);
    let seed = 1;
    let start = Instant::now();
    let mut renderer = CoreRenderer::with_options(prepared, EstimatorKind::Spcbpt, depth, seed, &cache).expect("configuration");
    let mut film = Film::new(w, h);
    let config = DriverConfig { progress: false, ..DriverConfig::with_threads(rayon::current_num_threads()) };
    let params = RenderParams { max_depth: MaxDepth(depth), seed, heuristic: Heuristic::Power, ..RenderParams::default() };
    let mut total: Option<ConnectionSums> = None;
    let mut light_x: Vec<(f64, u32)> = Vec::new();
    // Stage-2 spread (weighted sums of the effective share and of n·max P_r, the weight)
    // and Q's check (Σ|Q̂ − Q|, ΣQ).
    let (mut ess, mut peak, mut spread_weight) = (0.0f64, 0.0f64, 0.0f64);
    let mut q_sum: Vec<f64> = Vec::new();
    for pass in 0..passes {
        let limits = Limits { spp: pass + 1, deadline: None, interrupt: None, first_pass: 0 };
        renderer.render(&mut film, limits, config, start).expect("render");
        let Renderer::Spcbpt(s) = &renderer.renderer else { panic!("not SPCBPT (the plan is not applied here)") };
        let model = s.model.as_ref().expect("trained");
        let scene = &renderer.prepared.scene;
        let accel = &renderer.prepared.accel;
        let chunks: Vec<std::ops::Range<u32>> = (0..w * h).step_by(256).map(|a| a..(a + 256).min(w * h)).collect();
        let parts: Vec<ConnectionSums> = chunks
            .into_par_iter()
            .map(|range| {
                let mut part = ConnectionSums::new(model);
                connection_sums(scene, accel, &params, model, &s.cache, pass, range, &mut part);
                part
            })
            .collect();
        let sum = total.get_or_insert_with(|| ConnectionSums::new(model));
        for p in &parts {
            sum.add(p);
        }
        for (l, table) in s.cache.vertex_tables.iter().enumerate() {
            let total = table.as_ref().map_or(0.0, |t| t.total_weight());
            if let Some(t) = table {
                let n = t.len();
                let (sum2, max) = (0..n).fold((0.0f64, 0.0f32), |(a, m), i| (a + (t.pmf(i) as f64).powi(2), m.max(t.pmf(i))));
                if sum2 > 0.0 && total > 0.0 {
                    ess += total / (n as f64 * sum2);
                    peak += total * n as f64 * max as f64;
                    spread_weight += total;
                }
            }
            if cache.reuse == 0 {
                q_sum.resize(model.q.len(), 0.0);
                let m = s.cache.effective_paths.get(l).copied().unwrap_or(0.0);
                if let Some(slot) = q_sum.get_mut(l) {
                    *slot += if m > 0.0 { total / m } else { 0.0 };
                }
            }
        }
        // Light subspaces' mean x over this pass's cached vertices.
        if light_x.is_empty() {
            light_x = vec![(0.0, 0); model.classifier.n_light as usize];
        }
        for l in 0..light_x.len() {
            let mut i = 0;
            while let Some((light, _)) = s.cache.candidate(l, i) {
                if let Some(v) = light.last() {
                    light_x[l].0 += v.p.x as f64;
                    light_x[l].1 += 1;
                }
                i += 1;
                if i > 100_000 {
                    break;
                }
            }
        }
    }
    let Renderer::Spcbpt(s) = &renderer.renderer else { unreachable!() };
    let model = s.model.as_ref().expect("trained");
    let sums = total.expect("at least one pass");
    let d = distance(&model.gamma, &sums);
    println!(
        "steps {} batch {} losses {:?}\nKL(oracle||Γ) {:.3} nats, KL(oracle||uniform) {:.3} nats, Γ mass on light subspaces with no contribution {:.3}, {} eye subspaces with a contribution",
        s.report.steps, s.report.batch, s.report.losses, d.kl, d.kl_uniform, d.wasted, d.columns
    );
    println!(
        "stage 2: effective share of candidates {:.3}, n·max P_r {:.1} (weighted by f_y/p)",
        ess / spread_weight.max(1e-300),
        peak / spread_weight.max(1e-300)
    );
    if cache.reuse == 0 {
        let q: Vec<f64> = model.q.iter().map(|&q| q as f64).collect();
        let mean: Vec<f64> = q_sum.iter().map(|v| v / passes as f64).collect();
        let (diff, total): (f64, f64) = mean.iter().zip(&q).fold((0.0, 0.0), |(d, t), (m, q)| (d + (m - q).abs(), t + q));
        println!(
            "Q: the passes' mean Σ f_y/p / M per subspace against Q: totals {:.4} / {:.4}, relative L1 distance {:.4}",
            mean.iter().sum::<f64>(),
            total,
            diff / total.max(1e-300)
        );
    }
    // Orders: eye subspaces by their vertices' mean x, light subspaces by their cached vertices' mean x.
    let mean = |(sx, n): (f64, u64)| if n > 0 { sx / n as f64 } else { f64::INFINITY };
    let mut eye: Vec<usize> = (0..sums.n_eye).collect();
    eye.sort_by(|&a, &b| mean((sums.eye_positions[a][0], sums.eye_vertices[a])).total_cmp(&mean((sums.eye_positions[b][0], sums.eye_vertices[b]))));
    let mut light: Vec<usize> = (0..sums.n_light).collect();
    light.sort_by(|&a, &b| mean((light_x[a].0, light_x[a].1 as u64)).total_cmp(&mean((light_x[b].0, light_x[b].1 as u64))));
    let eye_wall = eye.iter().position(|&e| mean((sums.eye_positions[e][0], sums.eye_vertices[e])) > 1.0);
    let light_wall = light.iter().position(|&l| mean((light_x[l].0, light_x[l].1 as u64)) > 1.0);
    write_heatmap(&out.join("heatmap.png"), model, &sums, &eye, &light, eye_wall, light_wall);
    println!("wrote {}", out.join("heatmap.png").display());
}

/// Blue–white–red for log10(n · v) in [−2, 2]; black for None.
fn colour(v: Option<f64>) -> [u8; 3] {
    let Some(v) = v else { return [0, 0, 0] };
    let t = (v.log10().clamp(-2.0, 2.0) / 2.0) as f32;
    let c = |x: f32| (255.0 * x.clamp(0.0, 1.0)) as u8;
    if t < 0.0 { [c(1.0 + t), c(1.0 + t), 255] } else { [255, c(1.0 - t), c(1.0 - t)] }
}

fn write_heatmap(
    path: &std::path::Path,
    model: &ember_core::estimators::spcbpt::Model,
    sums: &ConnectionSums,
    eye: &[usize],
    light: &[usize],
    eye_wall: Option<usize>,
    light_wall: Option<usize>,
) {
    let (nl, ne) = (sums.n_light, sums.n_eye);
    let gap = 8;
    let (w, h) = (2 * nl + gap, ne);
    let mut img = vec![64u8; w * h * 3];
    for (row, &e) in eye.iter().enumerate() {
        let column = sums.column(e);
        for (col, &l) in light.iter().enumerate() {
            let g = model.gamma.get(l as u32, e as u32) as f64 * nl as f64;
            let o = column.as_ref().map(|c| c[l] * nl as f64).filter(|&v| v > 0.0);
            for (x, rgb) in [(col, colour(Some(g))), (nl + gap + col, colour(o))] {
                let mut rgb = rgb;
                if Some(row) == eye_wall || Some(col) == light_wall {
                    rgb = [128, 128, 128];
                }
                img[(row * w + x) * 3..(row * w + x) * 3 + 3].copy_from_slice(&rgb);
            }
        }
    }
    let file = std::fs::File::create(path).expect("create heatmap");
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w as u32, h as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.write_header().expect("png header").write_image_data(&img).expect("png data");
}
