//! `ember suite`: every estimator on every scene of the benchmark suite at equal time,
//! threads, seeds and depth (each scene's own `max_depth`), with error-against-time
//! plots per scene and one markdown table.
//!
//! The table gives, per scene and estimator, relMSE and MAPE at the end of the budget
//! (seed-averaged), the passes reached, and the time to reach the MAPE target
//! max(12 %, 2 × the reference's own MAPE floor) — "not reached" with the last value
//! when the budget ends first. Losses are published as they come.

use std::fmt::Write as _;
use std::path::PathBuf;

use crate::cli::{CacheArgs, EstimatorKind, SuiteArgs};
use crate::convergence::{self, ConvergenceSetup};
use crate::setup;
use ember_formats::error_time::{self, Checkpoint, Reference};

/// One scene's outcome.
#[derive(Clone, Debug)]
pub struct SceneResult {
    pub name: String,
    pub floor: Option<(f64, f64)>,
    pub points: Vec<Checkpoint>,
}

/// The scenes to run: sub-folders with a scene.xml of every folder in `dirs`, sorted by
/// name, filtered by `only`. Two scenes of one name (in different folders) are an error:
/// names key the tables and plots.
pub fn scene_folders(dirs: &[PathBuf], only: &[String]) -> Result<Vec<PathBuf>, String> {
    let mut v: Vec<PathBuf> = Vec::new();
    for dir in dirs {
        let entries = std::fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        v.extend(
            entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.join("scene.xml").is_file())
                .filter(|p| only.is_empty() || p.file_name().is_some_and(|n| only.iter().any(|o| n == o.as_str()))),
        );
    }
    v.sort_by(|a, b| a.file_name().cmp(&b.file_name()).then_with(|| a.cmp(b)));
    if let Some(w) = v.windows(2).find(|w| w[0].file_name() == w[1].file_name()) {
        return Err(format!("two scenes are named {:?}: {} and {}", w[0].file_name().unwrap_or_default(), w[0].display(), w[1].display()));
    }
    let names = || dirs.iter().map(|d| d.display().to_string()).collect::<Vec<_>>().join(", ");
    // Every --only name must be found (`--only nonexist` said there were no scene folders).
    let missing: Vec<&str> = only.iter().map(String::as_str).filter(|o| !v.iter().any(|p| p.file_name().is_some_and(|n| n == *o))).collect();
    if !missing.is_empty() {
        return Err(format!("--only {}: no such scene folder (with scene.xml) under {}", missing.join(", "), names()));
    }
    if v.is_empty() {
        return Err(format!("no scene folders (with scene.xml) under {}", names()));
    }
    Ok(v)
}

/// The MAPE target of the SPCBPT comparison: max(12 %, 2 × the reference's floor).
pub fn mape_target(floor: Option<(f64, f64)>) -> f64 {
    floor.map_or(12.0, |f| (2.0 * f.1).max(12.0))
}

/// Run the suite; progress lines go to stderr.
pub fn run(args: &SuiteArgs, threads: usize) -> Result<Vec<SceneResult>, String> {
    crate::convergence::check_distinct(&args.estimators)?;
    let plots_dir = args.output.with_extension("");
    let mut results = Vec::new();
    for folder in scene_folders(&args.scenes, &args.only)? {
        let name = folder.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let reference = Reference::load(&folder.join("reference.exr"))?;
        let setup = ConvergenceSetup {
            estimators: args.estimators.clone(),
            budget_seconds: args.budget,
            seeds: args.seeds,
            threads,
            max_depth: None,
            memory_limit: args.memory_limit,
            options: CacheArgs::default(),
        };
        let scene_file = folder.join("scene.xml");
        let prepare = setup::preparer(&scene_file, &args.defines.pairs);
        let points = convergence::measure(&setup, &reference, &prepare, |c| {
            eprintln!(
                "{name:12} {:5} seed {} at {:6.1} s: relMSE {:.4e}, MAPE {:6.2} % ({} passes)",
                c.estimator.name(),
                c.seed,
                c.elapsed_seconds,
                c.metrics.rel_mse,
                c.metrics.mape,
                c.passes
            );
        })?;
        convergence::write_outputs(&plots_dir, &name, &name, &points, &args.estimators, &reference)?;
        results.push(SceneResult { name, floor: reference.floor, points });
    }
    Ok(results)
}

/// The markdown report.
pub fn report(args: &SuiteArgs, threads: usize, results: &[SceneResult], command: &str) -> String {
    let plots = args.output.with_extension("");
    let plots_rel = plots.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let mut s = String::new();
    let _ = writeln!(s, "# Results: equal-time comparison on the benchmark suite\n");
    let _ = writeln!(s, "Reproduce with:\n\n    {command}\n");
    let _ = writeln!(
        s,
        "Every estimator ran {} s per scene and seed ({} seeds, seed-averaged), on {threads} threads, scene loading, BVH build and preprocessing included, each scene at its own `max_depth`; the estimators of a scene run interleaved, each on its own clock, so a load on the machine slows them alike. relMSE and MAPE are against the Mitsuba 3 reference (definitions in `host-cli/src/metrics.rs`); *floor* is the reference's own noise (from its two halves). *t(MAPE target)* is when the seed-averaged MAPE reached max(12 %, 2 × floor), interpolated log-log between the checkpoints (spaced by √2) around the crossing. Plots: `{plots_rel}/<scene>-relmse.svg`, `{plots_rel}/<scene>-mape.svg`; raw data: `{plots_rel}/<scene>.csv`.\n",
        args.budget, args.seeds
    );
    let _ = writeln!(s, "| scene | estimator | relMSE | MAPE % | passes | t(MAPE target) |");
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for r in results {
        let target = mape_target(r.floor);
        let floor = r.floor.map_or("n/a".to_string(), |f| format!("{:.2e} / {:.2} %", f.0, f.1));
        let best_rel = args.estimators.iter().filter_map(|&e| final_point(&r.points, e).map(|p| p.1)).fold(f64::INFINITY, f64::min);
        for &e in &args.estimators {
            let Some((_, rel, mape)) = final_point(&r.points, e) else { continue };
            let passes = r.points.iter().filter(|c| c.estimator == e).map(|c| c.passes).max().unwrap_or(0);
            let curve: Vec<(f64, f64)> = error_time::averaged(&r.points, e).iter().map(|p| (p.0, p.2)).collect();
            let reached = error_time::time_to_reach(&curve, target).map_or(format!("not reached ({mape:.1} %)"), |t| format!("{t:.1} s"));
            let mark = if rel == best_rel { " **best**" } else { "" };
            let _ = writeln!(s, "| {} (floor {floor}, target {target:.1} %) | {} | {rel:.3e}{mark} | {mape:.2} | {passes} | {reached} |", r.name, e.name());
        }
    }
    s
}

fn final_point(points: &[Checkpoint], e: EstimatorKind) -> Option<(f64, f64, f64)> {
    error_time::averaged(points, e).last().copied()
}

#[cfg(test)]
mod tests {
    use super::scene_folders;

    /// `--scenes` given twice takes the scenes of both folders, sorted by name and filtered
    /// by `--only`; one name in two folders is refused, naming both.
    #[test]
    fn scenes_from_several_folders() {
        let root = std::env::temp_dir().join(format!("ember-suite-folders-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        for (dir, name) in [("a", "cornell"), ("a", "zeta"), ("b", "alpha"), ("c", "cornell")] {
            let d = root.join(dir).join(name);
            std::fs::create_dir_all(&d).unwrap();
            std::fs::write(d.join("scene.xml"), "").unwrap();
        }
        std::fs::create_dir_all(root.join("b").join("no-scene")).unwrap();
        let names = |v: Vec<std::path::PathBuf>| v.iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect::<Vec<_>>();
        let both = scene_folders(&[root.join("a"), root.join("b")], &[]).unwrap();
        assert_eq!(names(both), ["alpha", "cornell", "zeta"]);
        let only = scene_folders(&[root.join("a"), root.join("b")], &["alpha".into()]).unwrap();
        assert_eq!(names(only), ["alpha"]);
        let e = scene_folders(&[root.join("a"), root.join("c")], &[]).unwrap_err();
        assert!(e.contains("two scenes are named") && e.contains("cornell"), "{e}");
        assert!(scene_folders(&[root.join("b")], &["zeta".into()]).is_err());
        let _ = std::fs::remove_dir_all(&root);
    }
}
