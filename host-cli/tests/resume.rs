//! Checkpoints and exact resume (issue 50): an image written with `--checkpoint`, or at an
//! interrupt, holds its exact sums; `--resume` renders the passes it lacks and writes the
//! bytes of one uninterrupted render of the same total.
#![cfg(unix)]

mod common;

use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::{finish, passes_held, signal, spawn, wait_for};

fn ember(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ember")).args(args).output().expect("run ember")
}

fn ok(o: &Output) {
    assert_eq!(o.status.code(), Some(0), "stderr: {}", String::from_utf8_lossy(&o.stderr));
}

fn fails(o: &Output) -> String {
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "stderr: {e}");
    e
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ember-resume-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn same_bytes(a: &Path, b: &Path) -> bool {
    std::fs::read(a).unwrap() == std::fs::read(b).unwrap()
}

/// For each estimator the resume tests cover, the `render` arguments at `size` (W, H) and
/// `seed`: PT, BDPT, VCM (merging on, on the caustic scene), SPCBPT (whose reuse FIFOs
/// are replayed) and BPF (whose kernel shrinks with the global pass index).
fn estimators(size: (&str, &str), seed: &str) -> Vec<(&'static str, Vec<String>)> {
    let caustic = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes/caustic/scene.xml");
    ["pt", "bdpt", "vcm", "spcbpt", "bpf"]
        .into_iter()
        .map(|e| {
            let mut args: Vec<String> =
                ["render", "-e", e, "--width", size.0, "--height", size.1, "--seed", seed, "--threads", "2"].into_iter().map(String::from).collect();
            if e == "vcm" {
                args.push(s(&caustic).to_string());
            }
            (e, args)
        })
        .collect()
}

/// A finished render extended, and a render written in checkpoint slices, equal one
/// render of the same total byte for byte (EXR and PNG), for PT, BDPT, VCM (merging on
/// the caustic scene), SPCBPT (whose reuse FIFOs are replayed) and BPF (whose kernel
/// shrinks with the global pass index). Injected bugs checked: resuming at pass 0 instead
/// of the image's end (the image's passes rendered twice) fails every estimator; not
/// replaying SPCBPT's earlier passes fails spcbpt.
#[test]
fn extending_a_render_equals_one_render() {
    let d = dir("extend");
    for (estimator, base) in estimators(("40", "30"), "3") {
        let base: Vec<&str> = base.iter().map(String::as_str).collect();
        let run = |extra: &[&str]| ember(&[base.as_slice(), extra].concat());
        let whole = d.join(format!("whole-{estimator}.exr"));
        ok(&run(&["--spp", "4", "-o", s(&whole)]));
        // Two passes with their sums, then extended to four into the same file.
        let grown = d.join(format!("grown-{estimator}.exr"));
        ok(&run(&["--spp", "2", "--checkpoint", "1000", "-o", s(&grown)]));
        let plain = d.join(format!("plain-{estimator}.exr"));
        ok(&run(&["--spp", "4", "--resume", s(&grown), "-o", s(&plain)]));
        assert!(same_bytes(&plain, &whole), "{estimator}: resumed EXR differs");
        assert!(same_bytes(&plain.with_extension("png"), &whole.with_extension("png")), "{estimator}: resumed PNG differs");
        // Slices of one pass each (a checkpoint after every pass), resumed to the same
        // total (nothing left to render) for the plain image.
        let sliced = d.join(format!("sliced-{estimator}.exr"));
        ok(&run(&["--spp", "4", "--checkpoint", "0.001", "-o", s(&sliced)]));
        ok(&run(&["--spp", "4", "--resume", s(&sliced), "-o", s(&sliced)]));
        assert!(same_bytes(&sliced, &whole), "{estimator}: a render in checkpoint slices differs");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// SIGTERM, then `--resume`: the passes written at the signal and the ones added equal
/// one render of the total, for PT, BDPT, VCM (merging on the caustic scene), SPCBPT and
/// BPF. Injected bug checked: writing the interrupted image without its sums (as before)
/// makes every resume fail with "not a partial image".
#[test]
fn a_terminated_render_resumes_exactly() {
    let d = dir("term");
    for (estimator, base) in estimators(("48", "36"), "5") {
        let base: Vec<&str> = base.iter().map(String::as_str).collect();
        let out = d.join(format!("out-{estimator}.exr"));
        let mut child = spawn(&[&base[..], &["--spp", "100000", "-o", s(&out)]].concat());
        let mut err = BufReader::new(child.stderr.take().unwrap());
        wait_for(&mut err, "progress: 1 pass");
        signal(&child, "TERM");
        let (status, rest, _) = finish(child, err);
        assert_eq!(status, Some(143), "{estimator}: {rest}");
        let held = passes_held(&rest, "SIGTERM");
        let total = (held + 2).to_string();
        let whole = d.join(format!("whole-{estimator}.exr"));
        ok(&ember(&[&base[..], &["--spp", &total, "-o", s(&whole)]].concat()));
        let resumed = d.join(format!("resumed-{estimator}.exr"));
        ok(&ember(&[&base[..], &["--spp", &total, "--resume", s(&out), "-o", s(&resumed)]].concat()));
        assert!(same_bytes(&resumed, &whole), "{estimator}: {held} passes resumed to {total} differ from one render");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// `--resume` continues only the render the image came from, and only an image with sums.
/// Injected bug checked: without the identity check in app::render, the seed row renders.
#[test]
fn resume_refuses_other_renders() {
    let d = dir("refuse");
    let same = ["--seed", "3", "--width", "16", "--height", "12"];
    let render = |extra: &[&str]| ember(&[&["render", "--threads", "2"][..], extra].concat());
    let image = d.join("a.exr");
    ok(&render(&[&same[..], &["--spp", "2", "--checkpoint", "1000", "-o", s(&image)]].concat()));
    let x = d.join("x.exr");
    let plain = d.join("plain.exr");
    ok(&render(&[&same[..], &["--spp", "2", "-o", s(&plain)]].concat()));
    for (settings, needle) in [
        (&["--seed", "4", "--width", "16", "--height", "12"][..], "it has seed 3, this render 4"),
        (&["-e", "bdpt", "--seed", "3", "--width", "16", "--height", "12"], "it has estimator pt, this render bdpt"),
        (&["--max-depth", "3", "--seed", "3", "--width", "16", "--height", "12"], "it has configuration max depth -1, this render max depth 3"),
        (&["--seed", "3", "--width", "32", "--height", "24"], "it has resolution 16x12, this render 32x24"),
        (&["--builtin", "glass-spheres", "--seed", "3", "--width", "16", "--height", "12"], "it is of another scene"),
        (&["-e", "auto", "--seed", "3", "--width", "16", "--height", "12"], "--estimator auto"),
    ] {
        let e = fails(&render(&[settings, &["--spp", "4", "--resume", s(&image), "-o", s(&x)]].concat()));
        assert!(e.contains(needle), "{settings:?}: {e}");
    }
    let e = fails(&render(&[&same[..], &["--spp", "4", "--resume", s(&plain), "-o", s(&x)]].concat()));
    assert!(e.contains("only images written with --checkpoint or at an interrupt"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}
