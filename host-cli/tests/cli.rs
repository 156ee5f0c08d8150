//! The `ember` binary: exit codes and messages for user input (never a panic).

use std::process::{Command, Output};

fn ember(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ember")).args(args).output().expect("run ember")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn help_and_version_exit_zero() {
    for args in [&["--help"][..], &["render", "--help"], &["--version"], &["render", "-h"]] {
        let o = ember(args);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {}", stderr(&o));
        assert!(!o.stdout.is_empty());
    }
    let help = String::from_utf8_lossy(&ember(&["render", "--help"]).stdout).into_owned();
    assert!(help.contains("--max-depth") && help.contains("bdpt"), "{help}");
}

#[test]
fn bad_input_exits_one_with_a_message() {
    for (args, needle) in [
        (&[][..], "Usage"),
        (&["render", "--spp", "0"], "--spp"),
        (&["render", "--estimator", "mlt"], "mlt"),
        (&["render", "--max-depth", "-7"], "--max-depth"),
        (&["frobnicate"], "frobnicate"),
        (&["render", "no-such-scene.xml"], "no-such-scene.xml"),
        (&["render", "-o", "picture.png"], ".exr"),
        (&["render", "-o", "/nonexistent-ember-dir/a.exr"], "does not exist"),
        // convergence and suite validate what render validates (a NaN budget looped
        // until memory ran out).
        (&["convergence", "scene.xml", "--budget", "nan"], "time budget"),
        (&["convergence", "scene.xml", "--budget=-3"], "time budget"),
        (&["convergence", "scene.xml", "--seeds", "0"], "--seeds"),
        (&["convergence", "scene.xml", "--threads", "0"], "--threads"),
        (&["convergence", "scene.xml", "--max-depth", "-2"], "--max-depth"),
        (&["suite", "--budget", "inf"], "time budget"),
        (&["suite", "--seeds", "0"], "--seeds"),
        (&["suite", "--threads", "0"], "--threads"),
        // SPCBPT/LVCBPT settings are checked by the core (a NaN mixture rendered 0.44× the
        // right mean).
        (&["render", "-e", "spcbpt", "--mixture", "nan", "--spp", "1"], "mixture"),
        (&["render", "-e", "spcbpt", "--learning-rate", "0", "--spp", "1"], "learning-rate"),
        (&["render", "-e", "lvcbpt", "--connections", "0", "--spp", "1"], "connections"),
        // Merging settings (issue 23): radius and α outside their ranges, conflicting radii.
        (&["render", "-e", "vcm", "--radius", "-1", "--spp", "1"], "radius"),
        (&["render", "-e", "ppm", "--radius-footprints", "nan", "--spp", "1"], "radius-footprints"),
        (&["render", "-e", "bpm", "--radius-scene", "0", "--spp", "1"], "radius-scene"),
        (&["render", "-e", "vcm", "--alpha", "0", "--spp", "1"], "alpha"),
        (&["render", "-e", "vcm", "--alpha", "1.5", "--spp", "1"], "alpha"),
        (&["render", "-e", "vcm", "--radius", "0.1", "--radius-scene", "0.01"], "cannot be used with"),
        (&["compare", "a.exr", "b.exr", "--region", "5,5,5,9"], "x0 < x1"),
        // The memory check (issue 13): refused before any large allocation, naming what
        // to lower (a 65536² film aborted with "memory allocation failed", rc 134).
        (&["render", "-e", "vcm", "--memory-limit", "1M", "--spp", "1"], "lower --light-paths"),
        (&["render", "--width", "65536", "--height", "65536", "--memory-limit", "1G"], "lower --width/--height"),
        (&["render", "--memory-limit", "0"], "at least 1 byte"),
        (&["render", "--memory-limit", "12Q"], "not a size"),
        // compare never overwrites an input.
        (&["compare", "a.exr", "b.exr", "--error-image", "a.exr"], "one of the images"),
    ] {
        let o = ember(args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: stderr lacks {needle:?}:\n{err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

/// A thread count far beyond the machine is capped with a warning, and the render runs.
#[test]
fn huge_thread_counts_are_capped() {
    let out = std::env::temp_dir().join(format!("ember-cli-threads-{}.exr", std::process::id()));
    let o = ember(&["render", "--threads", "100000", "--spp", "1", "--width", "8", "--height", "8", "-o", out.to_str().unwrap()]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.contains("capped at"), "{err}");
    let _ = std::fs::remove_file(&out);
    let _ = std::fs::remove_file(out.with_extension("png"));
}
