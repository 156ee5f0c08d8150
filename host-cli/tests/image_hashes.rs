//! Golden image hashes: every estimator, on the built-in Cornell box and two suite scene
//! files, at a fixed seed, resolution and pass count, rendered through the CLI host on 1
//! and 2 threads. The hash covers the bits of the film's f64 sums, its pass count and its
//! discarded-sample count, so any change to any random stream, any strategy, any weight
//! or the order of any f64 addition changes it.
//!
//! Purpose: refactors that must not change a single bit (the render-protocol move of
//! issue 12) prove it here. A deliberate numeric change updates the table in the same
//! commit, after checking per-block agreement with the old images (say so in the commit).
//! `EMBER_PRINT_HASHES=1 cargo test --release -p ember-cli --test image_hashes -- --nocapture`
//! prints the current table.
//!
//! Recorded on the code before the render-protocol change (commit e5412a9) and seen
//! passing there.

use std::path::PathBuf;
use std::time::Instant;

use ember_cli::cli::{CacheArgs, EstimatorArg, RenderArgs};
use ember_cli::driver::{self, DriverConfig, Limits};
use ember_cli::estimators::{CoreRenderer, PreparedScene, prepare_builtin, prepare_file};
use ember_cli::film::Film;

const PASSES: u32 = 3;
const SEED: u64 = 11;

fn scene_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes").join(name).join("scene.xml")
}

fn cache_args() -> CacheArgs {
    CacheArgs { light_paths: Some(200), dataset: Some(2000), q_paths: Some(2000), subspaces: Some(32), batch: 200, ..CacheArgs::default() }
}

/// FNV-1a over 64-bit words.
fn fnv(words: impl Iterator<Item = u64>) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for w in words {
        for b in w.to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}

fn film_hash(film: &Film) -> u64 {
    let sums = film.sums().iter().flat_map(|p| p.iter().map(|v| v.to_bits()));
    fnv(sums.chain([film.passes() as u64, film.discarded()]))
}

fn prepared(scene: &str) -> PreparedScene {
    match scene {
        "builtin" => {
            let args = RenderArgs { width: Some(32), height: Some(32), ..test_args() };
            prepare_builtin(&args).expect("built-in scene")
        }
        name => prepare_file(&scene_path(name), Some(32), Some(24), Vec::new()).expect("scene loads"),
    }
}

fn test_args() -> RenderArgs {
    use clap::Parser;
    match ember_cli::cli::Cli::parse_from(["ember", "render"]).command {
        ember_cli::cli::Command::Render(a) => a,
        _ => unreachable!(),
    }
}

fn render_hash(scene: &str, estimator: EstimatorArg, threads: usize) -> u64 {
    let depth = if scene == "builtin" { -1 } else { 6 };
    let renderer = CoreRenderer::with_options(prepared(scene), estimator, depth, SEED, &cache_args());
    let mut film = Film::new(renderer.prepared.scene.camera.width(), renderer.prepared.scene.camera.height());
    let config = DriverConfig { progress: false, ..DriverConfig::with_threads(threads) };
    driver::render(&renderer, &mut film, Limits { spp: PASSES, deadline: None }, config, Instant::now()).expect("render");
    film_hash(&film)
}

/// (scene, estimator, hash).
const GOLDEN: &[(&str, &str, u64)] = &[
    ("builtin", "pt", 0xb12d390ebbb86936),
    ("builtin", "lt", 0x4698e34bbffdd7c7),
    ("builtin", "bdpt", 0x2a170f1eef90e281),
    ("builtin", "lvcbpt", 0x48cc7907c9c06132),
    ("builtin", "spcbpt", 0x46619e438bc6a4d8),
    ("ajar", "pt", 0x34d3ff88304dfbfd),
    ("ajar", "lt", 0x405569d79484bc7f),
    ("ajar", "bdpt", 0xe16524b810d32b8e),
    ("ajar", "lvcbpt", 0x27f2104a103e9b56),
    ("ajar", "spcbpt", 0xc2ec77388b87e487),
    ("veach-mis", "pt", 0xfe87655efec906b5),
    ("veach-mis", "lt", 0xaa51f60cbb891409),
    ("veach-mis", "bdpt", 0x4b1e7def24a986a5),
    ("veach-mis", "lvcbpt", 0x2a76d653e4028f7e),
    ("veach-mis", "spcbpt", 0x5bc7f58f56d0e318),
];

const SCENES: [&str; 3] = ["builtin", "ajar", "veach-mis"];
const ESTIMATORS: [EstimatorArg; 5] = [EstimatorArg::Pt, EstimatorArg::Lt, EstimatorArg::Bdpt, EstimatorArg::Lvcbpt, EstimatorArg::Spcbpt];

#[test]
fn images_match_their_recorded_hashes_on_one_and_two_threads() {
    let print = std::env::var_os("EMBER_PRINT_HASHES").is_some();
    let mut failures = Vec::new();
    for scene in SCENES {
        for estimator in ESTIMATORS {
            let one = render_hash(scene, estimator, 1);
            let two = render_hash(scene, estimator, 2);
            if print {
                println!("    (\"{scene}\", \"{}\", {one:#018x}),", estimator.name());
            }
            if one != two {
                failures.push(format!("{scene} {}: 1 thread {one:#018x}, 2 threads {two:#018x}", estimator.name()));
            }
            match GOLDEN.iter().find(|(s, e, _)| *s == scene && *e == estimator.name()) {
                Some(&(_, _, want)) if want != one => failures.push(format!("{scene} {}: hash {one:#018x}, recorded {want:#018x}", estimator.name())),
                Some(_) => {}
                None => failures.push(format!("{scene} {}: no recorded hash", estimator.name())),
            }
        }
    }
    assert!(failures.is_empty(), "image hashes changed:\n{}", failures.join("\n"));
}
