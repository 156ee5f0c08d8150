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
    ] {
        let o = ember(args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: stderr lacks {needle:?}:\n{err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}
