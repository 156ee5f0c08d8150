//! Split renders (issue 22, docs/distributed.md): for every estimator, passes 0..7 split
//! into the four task shares 0..2, 2..4, 4..6, 6..7, each rendered by its own renderer
//! (its own setup, as on another machine), written as a partial image, read back and
//! merged in a shuffled order, equal the single render of 0..7 bit for bit: the exact
//! sums, the pass count and the tallies.
//!
//! Injected bugs checked (each run once, reverted):
//! - SPCBPT without the replay of earlier passes' light-path phase (`replay_pass`
//!   returning false): its tasks past the first start with empty reuse FIFOs and the
//!   merged sums differ from the whole render's (`spcbpt` fails here).
//! - Each task numbering its passes from 0 (`first_pass` ignored by the driver): fails
//!   (the tasks render passes 0..B instead of A..B).
//!
//! Why f64 sums could not do this: `core/src/render/film.rs`'s grouping test.

use std::time::Instant;

use ember_cli::cli::{CacheArgs, EstimatorKind, RenderArgs};
use ember_cli::distributed::{self, PartialHeader, PassRange};
use ember_cli::estimators::CoreRenderer;
use ember_cli::film::Film;
use ember_cli::progress::DriverConfig;
use ember_cli::setup::prepare_builtin;
use ember_host::driver::Limits;

const TOTAL: u32 = 7;
const TASKS: u32 = 4;
const SEED: u64 = 29;

fn cache_args() -> CacheArgs {
    CacheArgs { light_paths: Some(150), dataset: Some(1500), q_paths: Some(1500), subspaces: Some(24), batch: 150, reuse: 40, ..CacheArgs::default() }
}

fn args() -> RenderArgs {
    use clap::Parser;
    match ember_cli::cli::Cli::parse_from(["ember", "render", "--width", "20", "--height", "16"]).command {
        ember_cli::cli::Command::Render(a) => a,
        _ => unreachable!(),
    }
}

/// Passes `range` of `estimator` on the built-in box, from a renderer of its own.
fn render(estimator: EstimatorKind, range: PassRange) -> (CoreRenderer, Film) {
    let prepared = prepare_builtin(&args()).expect("built-in scene");
    let mut r = CoreRenderer::with_config(prepared, cache_args().config_for(estimator), 6, SEED, 2).expect("valid configuration");
    let mut film = Film::new(r.width(), r.height());
    let limits = Limits { spp: range.end, deadline: None, interrupt: None, first_pass: range.start };
    r.render(&mut film, limits, DriverConfig { progress: false, ..DriverConfig::with_threads(2) }, Instant::now()).expect("render");
    assert_eq!(film.passes(), range.len());
    (r, film)
}

#[test]
fn four_task_shares_merge_into_the_single_render_for_every_estimator() {
    let dir = std::env::temp_dir().join(format!("ember-split-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut failures = Vec::new();
    for estimator in EstimatorKind::ALL {
        let (_, whole) = render(estimator, PassRange { start: 0, end: TOTAL });
        // Shuffled: the merge must not depend on the order of the parts.
        let mut paths = Vec::new();
        for task in [2, 0, 3, 1] {
            let range = PassRange::of_task(task, TASKS, TOTAL).unwrap();
            let (r, film) = render(estimator, range);
            let id = r.identity();
            let header = PartialHeader {
                program: ember_host::program_version(),
                scene: id.scene,
                scene_hash: id.scene_hash,
                estimator: id.estimator,
                config: id.config,
                seed: id.seed,
                width: film.width(),
                height: film.height(),
                passes: range,
                total: TOTAL,
                tallies: film.tallies(),
            };
            let path = dir.join(format!("{}-{task}.exr", estimator.name()));
            distributed::write_partial(&path, &header, &film).expect("write part");
            paths.push(path);
        }
        let (header, merged) = distributed::merge_parts(&paths, distributed::Cover::All).expect("parts merge");
        assert_eq!(header.passes, PassRange { start: 0, end: TOTAL });
        if merged != whole {
            let differing = merged.exact_sums().iter().zip(whole.exact_sums()).filter(|(a, b)| a != b).count();
            failures.push(format!("{}: {differing} of {} pixels differ", estimator.name(), whole.pixels()));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(failures.is_empty(), "split renders differ from the whole render: {failures:?}");
}
