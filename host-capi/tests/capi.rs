//! The C API from Rust, through the exported functions: with the built-in BVH on the
//! built-in Cornell box the image is bit-identical to the CLI's (`ember render
//! --builtin cornell-box`) for the same estimator and seed; a host mapping the phases on
//! its own threads gets the same bits again; handles are generation-checked.
//!
//! Injected bug checked (run once, reverted): the C API's settings combining PT's
//! techniques with the balance heuristic instead of the CLI's power heuristic: PT's
//! image differs from the CLI's (every lit pixel).
#![allow(unsafe_code)]

use std::ffi::CString;
use std::time::Instant;

use ember_capi::EmberStatus;
use ember_capi::ffi::*;
use ember_cli::estimators::CoreRenderer;
use ember_cli::progress::DriverConfig;
use ember_core::estimators::EstimatorKind;
use ember_core::render::Film;
use ember_host::driver::Limits;
use ember_host::scene::PreparedScene;

const W: u32 = 40;
const H: u32 = 32;
const PASSES: u32 = 3;

fn cli_image(estimator: EstimatorKind, seed: u64) -> Vec<[f32; 3]> {
    let (scene, geometry, _) = ember_core::scene::builtin::cornell_box(W, H).build().unwrap();
    let accel = ember_host::accel::Accel::new(&geometry);
    let prepared = PreparedScene { name: "box".into(), scene, accel, max_depth: None, spp: None, warnings: Vec::new(), inputs: Vec::new() };
    let mut r = CoreRenderer::with_config(prepared, estimator.default_config(), -1, seed, 2).unwrap();
    let mut film = Film::new(W, H);
    let limits = Limits { spp: PASSES, deadline: None, interrupt: None, first_pass: 0 };
    r.render(&mut film, limits, DriverConfig { threads: 2, progress: false }, Instant::now()).unwrap();
    film.to_rgb_f32()
}

fn builtin_renderer(estimator: &str, seed: u64) -> (EmberScene, EmberRenderer) {
    builtin_renderer_with(estimator, seed, 2, "")
}

fn builtin_renderer_with(estimator: &str, seed: u64, threads: u32, options: &str) -> (EmberScene, EmberRenderer) {
    let (scene, renderer) = builtin_renderer_sized(W, H, estimator, seed, threads, options);
    (scene, renderer.unwrap_or_else(|s| panic!("renderer: {s:?}")))
}

/// The built-in box at `width` × `height` and a renderer for it with the built-in BVH
/// (or the status that refused it).
fn builtin_renderer_sized(
    width: u32,
    height: u32,
    estimator: &str,
    seed: u64,
    threads: u32,
    options: &str,
) -> (EmberScene, Result<EmberRenderer, EmberStatus>) {
    let (mut scene, mut renderer) = (0, 0);
    let name = CString::new("cornell-box").unwrap();
    assert_eq!(unsafe { ember_scene_builtin(name.as_ptr(), width, height, &mut scene) }, EmberStatus::Ok);
    let (est, options) = (CString::new(estimator).unwrap(), CString::new(options).unwrap());
    let settings = EmberRenderSettings {
        estimator: est.as_ptr(),
        seed,
        max_depth: -1,
        threads,
        light_paths: 0,
        connections: 0,
        radius_footprints: 0.0,
        options: options.as_ptr(),
    };
    match unsafe { ember_renderer_create(scene, &settings, std::ptr::null(), &mut renderer) } {
        EmberStatus::Ok => (scene, Ok(renderer)),
        status => (scene, Err(status)),
    }
}

fn image(r: EmberRenderer) -> Vec<[f32; 3]> {
    let mut rgb = vec![0.0f32; (W * H * 3) as usize];
    assert_eq!(unsafe { ember_renderer_image(r, rgb.as_mut_ptr(), rgb.len()) }, EmberStatus::Ok);
    rgb.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect()
}

#[test]
fn the_builtin_box_is_bit_identical_to_the_cli_for_every_estimator() {
    for kind in [EstimatorKind::Pt, EstimatorKind::Bdpt, EstimatorKind::Lvcbpt, EstimatorKind::Vcm] {
        let (scene, r) = builtin_renderer(kind.name(), 5);
        assert_eq!(ember_render_passes(r, PASSES), EmberStatus::Ok);
        let (mine, cli) = (image(r), cli_image(kind, 5));
        let differing = mine.iter().zip(&cli).filter(|(a, b)| a != b).count();
        assert_eq!(differing, 0, "{}: {differing} of {} pixels differ from the CLI's", kind.name(), cli.len());
        assert_eq!(ember_renderer_destroy(r), EmberStatus::Ok);
        assert_eq!(ember_scene_destroy(scene), EmberStatus::Ok);
    }
}

/// The phase protocol on the host's own threads: chunks mapped concurrently from four
/// threads, in scrambled order, reduce to the same bits as `ember_render_passes`.
#[test]
fn host_threads_mapping_phases_give_the_same_bits() {
    let (scene, by_passes) = builtin_renderer("lvcbpt", 9);
    assert_eq!(ember_render_passes(by_passes, PASSES), EmberStatus::Ok);
    let (_, by_phases) = builtin_renderer("lvcbpt", 9);
    for pass in 0..PASSES {
        assert_eq!(ember_pass_start(by_phases, pass), EmberStatus::Ok);
        loop {
            let mut info = EmberPhaseInfo::default();
            match unsafe { ember_phase_begin(by_phases, &mut info) } {
                EmberStatus::Done => break,
                EmberStatus::Ok => {}
                other => panic!("begin: {other:?}"),
            }
            std::thread::scope(|s| {
                for t in 0..4u32 {
                    s.spawn(move || {
                        for c in (0..info.chunks).rev().filter(|c| c % 4 == t) {
                            assert_eq!(ember_phase_map(by_phases, c), EmberStatus::Ok);
                        }
                    });
                }
            });
            assert_eq!(ember_phase_end(by_phases), EmberStatus::Ok);
        }
    }
    let mut passes = 0;
    assert_eq!(unsafe { ember_renderer_passes(by_phases, &mut passes) }, EmberStatus::Ok);
    assert_eq!(passes, PASSES);
    assert!(image(by_phases) == image(by_passes), "the phase calls give other bits than ember_render_passes");
    ember_renderer_destroy(by_passes);
    ember_renderer_destroy(by_phases);
    ember_scene_destroy(scene);
}

/// A destroyed handle stays dead after its slot is reused.
#[test]
fn handles_are_generation_checked() {
    let mut reg = ember_capi::Registry::default();
    let a = reg.insert("a");
    assert_eq!(reg.remove(a), Some("a"));
    let b = reg.insert("b");
    assert_eq!(a as u32, b as u32, "the slot is reused");
    assert_ne!(a, b);
    assert_eq!(reg.get(a), None);
    assert_eq!(reg.remove(a), None);
    assert_eq!(reg.get(b), Some(&"b"));
    assert_eq!(reg.get(0), None);
}

/// The options string sets the same configuration the CLI's flags do.
#[test]
fn options_configure_the_estimator_as_the_cli_flags_do() {
    use clap::Parser;
    let settings = ember_capi::Settings {
        estimator: "spcbpt".into(),
        seed: 0,
        max_depth: 5,
        threads: 1,
        light_paths: 150,
        connections: 0,
        radius_footprints: 0.0,
        options: "subspaces=24  dataset=2000 reuse=0 light-source-share=0".into(),
    };
    let ember_capi::Config { estimator: config, params, .. } = settings.config().expect("valid options");
    let cli = ember_cli::cli::Cli::parse_from([
        "ember",
        "render",
        "-e",
        "spcbpt",
        "--light-paths",
        "150",
        "--subspaces",
        "24",
        "--dataset",
        "2000",
        "--reuse",
        "0",
        "--light-source-share",
        "0",
    ]);
    let ember_cli::cli::Command::Render(args) = cli.command else { unreachable!() };
    assert_eq!(config, args.cache.config_for(EstimatorKind::Spcbpt));
    assert_eq!(params.max_depth.0, 5);
    let bad = ember_capi::Settings { options: "subspaces=24 subspaces=30".into(), ..settings };
    assert_eq!(bad.config().unwrap_err().status, EmberStatus::InvalidConfig, "a repeated option is refused");
}

/// `threads` is capped as `ember render --threads` caps it (4 × the cores, at most 1024),
/// and `UINT32_MAX` renders. Injected bug seen to fail (run once, reverted): the cap
/// removed (threads taken as given): threads = 64 gave 64 against the CLI's 8 on 2
/// cores. (The same bug in errors.c's "threads UINT32_MAX" row aborted the program.)
#[test]
fn threads_are_capped_as_the_cli_caps_them() {
    for n in [1, 2, 3, 7, 64, 1024, 1025, u32::MAX] {
        assert_eq!(ember_capi::thread_count(n), ember_cli::cli::thread_count(Some(n)), "threads = {n}");
    }
    assert_eq!(ember_capi::thread_count(0), ember_cli::cli::thread_count(None));
    let (scene, r) = builtin_renderer_with("pt", 1, u32::MAX, "");
    assert_eq!(ember_render_passes(r, 1), EmberStatus::Ok);
    ember_renderer_destroy(r);
    ember_scene_destroy(scene);
}

/// The memory check before the film: the `memory-limit` option replaces the memory
/// available, and the message says what to lower in this API's words. Injected bug seen
/// to fail (run once, reverted): `check_memory` not called: status OK, and a 65536 ×
/// 65536 camera aborted the test process (the film's 192 GiB of sums).
#[test]
fn renders_past_the_memory_limit_are_refused_before_allocating() {
    let settings = |estimator: &str, light_paths: u32, options: &str| ember_capi::Settings {
        estimator: estimator.into(),
        seed: 0,
        max_depth: -1,
        threads: 1,
        light_paths,
        connections: 0,
        radius_footprints: 0.0,
        options: options.into(),
    };
    let scene = ember_capi::SceneData::builtin("cornell-box", W, H).unwrap();
    // The film alone: 40 × 32 pixels × 60 bytes = 75 KiB.
    let config = settings("pt", 0, "memory-limit=64K").config().unwrap();
    assert_eq!(config.memory_limit, Some(64 << 10));
    let e = ember_capi::check_memory(&scene, &config.estimator, config.memory_limit).unwrap_err();
    assert_eq!(e.status, EmberStatus::OutOfMemory);
    assert!(e.message.contains("more than the 64.0 KiB of the memory-limit option; lower the camera's width and height"), "{}", e.message);
    assert_eq!(ember_capi::check_memory(&scene, &config.estimator, Some(80 << 10)), Ok(()));
    let config = settings("vcm", 4_000_000, "memory-limit=1G").config().unwrap();
    let e = ember_capi::check_memory(&scene, &config.estimator, config.memory_limit).unwrap_err();
    assert!(e.message.ends_with("lower settings.light_paths"), "{}", e.message);
    let twice = settings("pt", 0, "memory-limit=1G memory-limit=2G").config().unwrap_err();
    assert_eq!((twice.status, twice.message.as_str()), (EmberStatus::InvalidConfig, "option 'memory-limit' is given twice"));
    // Through the C API, at the size that aborted: refused, whatever this machine has
    // (up to 240 GiB available).
    let (scene, r) = builtin_renderer_sized(65536, 65536, "pt", 1, 1, "");
    assert_eq!(r, Err(EmberStatus::OutOfMemory));
    ember_scene_destroy(scene);
}
