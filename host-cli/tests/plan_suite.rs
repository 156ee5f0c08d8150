//! Issue 21 "must show": on every suite scene the planned render agrees with the full
//! render per block. Rendered through the CLI host as `ember render` does (the Mitsuba
//! loader, the obvhs BVH, `CoreRenderer`, the driver and its film), at 32 pixels wide,
//! the depth the scene asks for capped at 8 (the same integral for both renders).
//!
//! Two estimators have techniques the plan may leave out:
//! - VCM (fixed radius 0.01 of the scene's bounding sphere, α = 1, 8192 light paths, so
//!   that merges carry much of the weight where they run): merging is left out
//!   where no specular–diffuse–specular chain exists. The full render then carries the
//!   kernel's bias, so blocks must agree within 5σ plus 4 % and the image mean within
//!   4σ plus 1 % (as `tests/vcm_estimator.rs` allows VCM against BDPT).
//! - SPCBPT: light-source bins left out for one compact emitter, or the estimator
//!   replaced by LVCBPT where the pilot finds connections rarely occluded. Both are
//!   unbiased, so every block and channel gets a two-sided z-test, Šidák-corrected over
//!   every comparison of the file.
//!
//! Where the plan changes nothing the two renders are the same render; the test then
//! checks that it really changed nothing (equal configurations). The decisions it found
//! are printed, so a change in the rules shows up in the log.
//!
//! Left out means never allocated: after its passes the planned VCM holds no photon,
//! grid or photon record.
//!
//! Measured: 13 of the 18 (scene, estimator) pairs change (VCM on the 7 scenes without
//! chains; SPCBPT on 6: bins left out on 4, LVCBPT instead on glossy and spot_mirror);
//! largest VCM mean difference spot_mirror +14 % (z = 2.85, the full render's merges
//! the noisier), about 25 s on 2 cores.
//!
//! Injected bug seen failing: the left-out merge still counted in VCM's balance
//! heuristic (`Vcm::techniques` returning η with merging off, no photons built): ajar
//! −14 % (z = −22.7), enclosed −23 % (z = −50.8), glossy −21 % (z = −17.4). With the
//! first setting tried (radius 0.003 of the scene, 768 light paths, η ≈ 0.2) the merge
//! carried too little weight and the same bug passed: hence the larger radius.

use std::path::PathBuf;
use std::time::Instant;

use ember_cli::progress::DriverConfig;

use ember_cli::estimators::CoreRenderer;
use ember_cli::film::Film;
use ember_cli::setup::prepare_file;
use ember_core::estimators::{EstimatorConfig, MergeMode, MergingConfig, SpcbptConfig};
use ember_core::merge::RadiusRule;
use ember_host::driver::Limits;
use ember_host::scene::PreparedScene;
use ember_tests::chi2::sidak;
use ember_tests::stats::{MeanVar, normal_two_sided_p};

const W: u32 = 32;
const BLOCK: u32 = 8;
const SEED: u64 = 7;
const PASSES: u32 = 40;
const SCENES: [&str; 9] = ["ajar", "caustic", "cornell-box", "enclosed", "glossy", "spot_mirror", "veach-bidir", "veach-mis", "window_env"];

fn load(scene: &str) -> PreparedScene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes").join(scene).join("scene.xml");
    prepare_file(&path, Some(W), None, Vec::new()).expect("scene loads")
}

fn vcm() -> EstimatorConfig {
    EstimatorConfig::Merging(
        MergeMode::Vcm,
        MergingConfig { light_paths: Some(8192), radius: RadiusRule::SceneFraction(0.01), alpha: 1.0, ..MergingConfig::DEFAULT },
    )
}

fn spcbpt() -> EstimatorConfig {
    EstimatorConfig::Spcbpt(SpcbptConfig {
        light_paths: Some(256),
        dataset: Some(3000),
        q_paths: Some(3000),
        subspaces: Some(64),
        reuse: 0,
        ..SpcbptConfig::DEFAULT
    })
}

/// Per-block, per-channel statistics of `passes` pass images, and the image mean's.
fn blocks(scene: &str, config: EstimatorConfig, depth: i32) -> (Vec<[MeanVar; 3]>, MeanVar, (u32, u32)) {
    let prepared = load(scene);
    let (w, h) = (prepared.scene.camera.width(), prepared.scene.camera.height());
    let mut renderer = CoreRenderer::with_config(prepared, config, depth, SEED, 2).expect("valid configuration");
    let mut film = Film::new(w, h);
    let (bw, bh) = (w.div_ceil(BLOCK), h.div_ceil(BLOCK));
    let mut previous = vec![[0.0f64; 3]; (w * h) as usize];
    let mut stats = vec![[MeanVar::default(); 3]; (bw * bh) as usize];
    let mut mean = MeanVar::default();
    let driver = DriverConfig { progress: false, ..DriverConfig::with_threads(2) };
    for pass in 0..PASSES {
        renderer.render(&mut film, Limits { spp: pass + 1, deadline: None, interrupt: None, first_pass: 0 }, driver, Instant::now()).expect("render");
        let mut block = vec![[0.0f64; 3]; stats.len()];
        let mut count = vec![0.0f64; stats.len()];
        let mut total = 0.0;
        for (i, (now, before)) in film.sums().iter().zip(previous.iter_mut()).enumerate() {
            let (x, y) = (i as u32 % w, i as u32 / w);
            let b = ((y / BLOCK) * bw + x / BLOCK) as usize;
            for c in 0..3 {
                block[b][c] += now[c] - before[c];
            }
            total += now[1] - before[1];
            count[b] += 1.0;
            *before = *now;
        }
        for ((s, v), n) in stats.iter_mut().zip(&block).zip(&count) {
            for c in 0..3 {
                s[c].push(v[c] / n);
            }
        }
        mean.push(total / (w * h) as f64);
    }
    assert_eq!(film.discarded(), 0, "{scene}: discarded samples");
    // Left out means never allocated: VCM without merging holds no photon, grid or record.
    if let (EstimatorConfig::Merging(MergeMode::Vcm, c), ember_core::estimators::Renderer::Merging(m)) = (config, &renderer.renderer)
        && !c.merging
    {
        assert_eq!((m.photons.capacity(), m.records.capacity(), m.grid.size_bytes()), (0, 0, 0), "{scene}: merging's storage allocated");
    }
    (stats, mean, (bw, bh))
}

#[test]
fn planned_renders_agree_with_full_renders_on_every_suite_scene() {
    let start = Instant::now();
    // Count the z-tests first (blocks × channels per unbiased pair) for the correction.
    let (mut jobs, mut tests) = (Vec::new(), 0usize);
    for scene in SCENES {
        let prepared = load(scene);
        let depth = match prepared.max_depth {
            Some(d) if (0..=8).contains(&d) => d,
            _ => 8,
        };
        let blocks_n = (W.div_ceil(BLOCK) * prepared.scene.camera.height().div_ceil(BLOCK)) as usize;
        for asked in [vcm(), spcbpt()] {
            let plan = ember_cli::plan::plan_for(&prepared, asked, depth, SEED, 2, ember_core::plan::pilot::DEFAULT_SAMPLES).expect("plan");
            println!("{scene} {}: {:?}", asked.kind().name(), plan.decision_lines());
            if plan.planned == asked {
                assert!(plan.decisions.iter().all(|d| d.kept), "{scene}: a technique left out, yet the configuration is unchanged");
                continue;
            }
            if matches!(asked, EstimatorConfig::Spcbpt(_)) {
                tests += blocks_n * 3;
            }
            jobs.push((scene, depth, asked, plan.planned));
        }
    }
    assert!(jobs.iter().any(|j| matches!(j.2, EstimatorConfig::Merging(..))), "some suite scene needs no merging");
    assert!(jobs.iter().any(|j| matches!(j.2, EstimatorConfig::Spcbpt(..))), "some suite scene's plan changes SPCBPT");
    let alpha = sidak(0.01, tests.max(1));
    let mut failures = Vec::new();
    for (scene, depth, asked, planned) in jobs {
        let (full, full_mean, _) = blocks(scene, asked, depth);
        let (plan, plan_mean, _) = blocks(scene, planned, depth);
        let sigma = (full_mean.std_error().powi(2) + plan_mean.std_error().powi(2)).sqrt();
        let rel_z = (plan_mean.mean() - full_mean.mean()) / sigma.max(1e-30);
        println!(
            "{scene} {} -> {}: image mean {:.5} vs {:.5} (z = {rel_z:.2})",
            asked.kind().name(),
            planned.kind().name(),
            plan_mean.mean(),
            full_mean.mean()
        );
        let unbiased = matches!(asked, EstimatorConfig::Spcbpt(_));
        if !unbiased && (plan_mean.mean() - full_mean.mean()).abs() > 4.0 * sigma + 0.01 * full_mean.mean() {
            failures.push(format!("{scene} vcm: image mean {} planned vs {} full (σ {sigma})", plan_mean.mean(), full_mean.mean()));
        }
        for (b, (f, p)) in full.iter().zip(&plan).enumerate() {
            for c in 0..3 {
                let se = (f[c].std_error().powi(2) + p[c].std_error().powi(2)).sqrt();
                let diff = p[c].mean() - f[c].mean();
                if unbiased {
                    if se == 0.0 {
                        if diff != 0.0 {
                            failures.push(format!("{scene} block {b} channel {c}: zero variance, {} vs {}", p[c].mean(), f[c].mean()));
                        }
                        continue;
                    }
                    let pz = normal_two_sided_p(diff / se);
                    if pz < alpha {
                        failures.push(format!("{scene} {} block {b} channel {c}: z = {:.2} (p = {pz:.2e} < {alpha:.2e})", planned.kind().name(), diff / se));
                    }
                } else if diff.abs() > 5.0 * se + 0.04 * f[c].mean() {
                    failures.push(format!("{scene} vcm block {b} channel {c}: {} planned vs {} full (σ {se})", p[c].mean(), f[c].mean()));
                }
            }
        }
    }
    println!("{:.1} s", start.elapsed().as_secs_f64());
    assert!(failures.is_empty(), "{failures:#?}");
}
