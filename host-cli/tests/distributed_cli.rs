//! `ember render --passes/--task-*` and `ember merge` as a user runs them: the merged
//! image equals the whole render's file byte for byte, and merge refuses mismatched,
//! overlapping and incomplete sets with messages naming the files and passes.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn ember(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_ember"));
    c.args(args);
    for var in ["SLURM_ARRAY_TASK_ID", "SLURM_ARRAY_TASK_MIN", "SLURM_ARRAY_TASK_COUNT", "JOB_COMPLETION_INDEX"] {
        c.env_remove(var);
    }
    c.envs(env.iter().copied());
    c.output().expect("run ember")
}

fn ok(o: &Output) -> String {
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn fails(o: &Output) -> String {
    assert_eq!(o.status.code(), Some(1), "stdout: {}", String::from_utf8_lossy(&o.stdout));
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ember-dist-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn same_bytes(a: &Path, b: &Path) -> bool {
    std::fs::read(a).unwrap() == std::fs::read(b).unwrap()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

const BASE: [&str; 10] = ["render", "-e", "bdpt", "--width", "24", "--height", "16", "--spp", "6", "--threads=2"];

fn render(extra: &[&str], env: &[(&str, &str)]) -> Output {
    let args: Vec<&str> = BASE.iter().copied().chain(extra.iter().copied()).collect();
    ember(&args, env)
}

#[test]
fn tasks_from_slurm_and_kubernetes_merge_into_the_whole_render_byte_for_byte() {
    let d = dir("tasks");
    let whole = d.join("whole.exr");
    ok(&render(&["-o", s(&whole)], &[]));

    // Slurm numbers this array 5-7; Kubernetes' index is 0-based; --passes names a range.
    let slurm = |id: &'static str| [("SLURM_ARRAY_TASK_ID", id), ("SLURM_ARRAY_TASK_MIN", "5"), ("SLURM_ARRAY_TASK_COUNT", "3")];
    let pattern = d.join("part-{task}.exr");
    for id in ["5", "6"] {
        let out = ok(&render(&["--task-from-env", "-o", s(&pattern)], &slurm(id)));
        assert!(out.contains("partial: passes"), "{out}");
    }
    // Task 2 of 3 holds passes 4..6: the same share from --passes and from Kubernetes.
    let k8s = d.join("k8s-{task}.exr");
    ok(&render(&["--task-from-env", "--task-count", "3", "-o", s(&k8s)], &[("JOB_COMPLETION_INDEX", "2")]));
    ok(&render(&["--passes", "4..6", "-o", s(&d.join("range-{passes}.exr"))], &[]));
    assert!(same_bytes(&d.join("k8s-2.exr"), &d.join("range-4-6.exr")), "same passes, same bytes");

    let merged = d.join("merged.exr");
    let parts = [d.join("part-0.exr"), d.join("part-1.exr"), d.join("k8s-2.exr")];
    let out = ok(&ember(&["merge", s(&parts[2]), s(&parts[0]), s(&parts[1]), "-o", s(&merged)], &[]));
    assert!(out.contains("merged     3 parts: passes 0..6 of 6"), "{out}");
    assert!(same_bytes(&merged, &whole), "merged EXR equals the whole render's");
    // In stages: parts 1 and 2 into one partial, then that with part 0.
    let stage = d.join("stage-1-2.exr");
    let out = ok(&ember(&["merge", "--partial", s(&parts[1]), s(&parts[2]), "-o", s(&stage)], &[]));
    assert!(out.contains("partial: passes 2..6 of 6"), "{out}");
    let staged = d.join("staged.exr");
    ok(&ember(&["merge", s(&stage), s(&parts[0]), "-o", s(&staged)], &[]));
    assert!(same_bytes(&staged, &whole), "a merge in stages equals the whole render");
    assert!(d.join("merged.png").is_file());

    // Re-running a task is idempotent: the same bytes again.
    let before = d.join("before.exr");
    std::fs::copy(&parts[1], &before).unwrap();
    ok(&render(&["--task-from-env", "-o", s(&pattern)], &slurm("6")));
    assert!(same_bytes(&parts[1], &before));
    // Parts never replace each other (issue 50): an array's tasks need {task} or
    // {passes} in -o, and another range is refused over an existing part. Injected bug
    // checked: without the header check in app::render the second render replaces part-1.
    let e = fails(&render(&["--task-from-env", "-o", s(&d.join("same.exr"))], &slurm("6")));
    assert!(e.contains("names neither {task} nor {passes}"), "{e}");
    let e = fails(&render(&["--passes", "0..1", "-o", s(&parts[1])], &[]));
    assert!(e.contains("part-1.exr' holds passes") && e.contains("of another task"), "{e}");
    assert!(same_bytes(&parts[1], &before));

    // Without --task-from-env the scheduler's variables are ignored: a whole render.
    let inside = d.join("inside-array.exr");
    ok(&render(&["-o", s(&inside)], &slurm("6")));
    assert!(same_bytes(&inside, &whole));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn merge_refuses_mismatched_overlapping_and_incomplete_sets() {
    let d = dir("refuse");
    let p = |name: &str| d.join(name);
    ok(&render(&["--passes", "0..3", "-o", s(&p("a.exr"))], &[]));
    ok(&render(&["--passes", "3..6", "-o", s(&p("b.exr"))], &[]));
    ok(&render(&["--passes", "2..6", "-o", s(&p("overlap.exr"))], &[]));
    ok(&render(&["--passes", "3..6", "--seed", "9", "-o", s(&p("seed9.exr"))], &[]));
    ok(&render(&["--passes", "3..6", "--max-depth", "3", "-o", s(&p("depth3.exr"))], &[]));
    ok(&render(&["--passes", "3..6", "--builtin", "glass-spheres", "-o", s(&p("other-scene.exr"))], &[]));
    let out = p("out.exr");
    let merge = |parts: &[&str]| {
        let mut args = vec!["merge"];
        args.extend(parts);
        args.extend(["-o", s(&out)]);
        fails(&ember(&args, &[]))
    };
    let (a, b) = (s(&p("a.exr")).to_string(), s(&p("b.exr")).to_string());

    let e = merge(&[&a]);
    assert!(e.contains("passes 3..6 of 6 are missing"), "{e}");
    // A staged merge needs a contiguous run: 0..3 and 4..6 leave 3..4 out.
    ok(&render(&["--passes", "4..6", "-o", s(&p("c.exr"))], &[]));
    let e = fails(&ember(&["merge", "--partial", &a, s(&p("c.exr")), "-o", s(&out)], &[]));
    assert!(e.contains("passes 3..4 of 6 are missing"), "{e}");
    let e = merge(&[&a, s(&p("overlap.exr"))]);
    assert!(e.contains("passes 2..6 of") && e.contains("overlap passes 0..3 of") && e.contains("a.exr"), "{e}");
    let e = merge(&[&a, s(&p("seed9.exr"))]);
    assert!(e.contains("seed9.exr' has seed 9, but") && e.contains("has 0"), "{e}");
    let e = merge(&[&a, s(&p("depth3.exr"))]);
    assert!(e.contains("depth3.exr' has configuration max depth 3, but") && e.contains("has max depth -1"), "{e}");
    let e = merge(&[&a, s(&p("other-scene.exr"))]);
    assert!(e.contains("other-scene.exr' has scene hash"), "{e}");
    // A plain image, a missing file, an output that is an input.
    ok(&render(&["-o", s(&p("plain.exr"))], &[]));
    let e = merge(&[&a, s(&p("plain.exr"))]);
    assert!(e.contains("plain.exr is not a partial image"), "{e}");
    let e = merge(&[&a, s(&p("nope.exr"))]);
    assert!(e.contains("nope.exr"), "{e}");
    let e = fails(&ember(&["merge", &a, &b, "-o", &a], &[]));
    assert!(e.contains("is one of the parts"), "{e}");
    assert!(!out.exists(), "nothing written on a refusal");

    // Options that cannot make a share.
    for (args, needle) in [
        (&["render", "--passes", "0..3"][..], "--spp"),
        (&["render", "--spp", "4", "--passes", "2..9"], "past the --spp total"),
        (&["render", "--spp", "4", "--passes", "3..3"], "empty"),
        (&["render", "--spp", "4", "--task-index", "4", "--task-count", "4"], "not below"),
        (&["render", "--spp", "2", "--task-index", "0", "--task-count", "3"], "cannot share"),
        (&["render", "--spp", "4", "--task-from-env"], "neither SLURM_ARRAY_TASK_ID"),
        (&["render", "--spp", "4", "--passes", "0..2", "-o", "p-{task}.exr"], "{task}"),
        (&["render", "--task-count", "4"], "--task-count needs"),
        (&["render", "--spp", "4", "--task-count", "4"], "--task-count needs"),
    ] {
        let e = String::from_utf8_lossy(&ember(args, &[]).stderr).into_owned();
        assert!(e.contains(needle), "{args:?}: {e}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// `ember train` once, `--model` in every task: the merge equals the render that trained
/// for itself, byte for byte; a model for another render, or a damaged one, is refused.
#[test]
fn tasks_load_one_trained_model() {
    let d = dir("model");
    let model = d.join("model.bin");
    let spc = ["-e", "spcbpt", "--width", "24", "--height", "16", "--light-paths", "120", "--dataset", "1200", "--subspaces", "16", "--threads=2"];
    let train: Vec<&str> = ["train", "--seed", "3"].into_iter().chain(spc).chain(["-o", s(&model)]).collect();
    let out = ok(&ember(&train, &[]));
    assert!(out.contains("trained    spcbpt"), "{out}");
    let render = |extra: &[&str]| {
        let seed = if extra.contains(&"--seed") { [].as_slice() } else { ["--seed", "3"].as_slice() };
        let args: Vec<&str> = ["render", "--spp", "6"].into_iter().chain(spc).chain(seed.iter().copied()).chain(extra.iter().copied()).collect();
        ember(&args, &[])
    };
    let whole = d.join("whole.exr");
    ok(&render(&["-o", s(&whole)]));
    let part = d.join("p-{task}.exr");
    for i in ["0", "1"] {
        let o = render(&["--model", s(&model), "--task-index", i, "--task-count", "2", "-o", s(&part)]);
        assert!(String::from_utf8_lossy(&o.stderr).contains("model loaded from"), "loaded, not trained");
        ok(&o);
    }
    let merged = d.join("merged.exr");
    ok(&ember(&["merge", s(&d.join("p-0.exr")), s(&d.join("p-1.exr")), "-o", s(&merged)], &[]));
    assert!(same_bytes(&merged, &whole), "tasks with the trained model equal the render that trained itself");

    let e = fails(&render(&["--model", s(&model), "--seed", "4", "-o", s(&d.join("x.exr"))]));
    assert!(e.contains("trained with seed 3, but this render has 4"), "{e}");
    let e = fails(&render(&["--model", s(&model), "--connections", "5", "-o", s(&d.join("x.exr"))]));
    // The field that differs, not two configuration dumps (issue 51).
    assert!(e.lines().any(|l| l.contains("trained with another configuration: connections 3, but this render has connections 5") && l.len() < 300), "{e}");
    let e = fails(&render(&["--model", s(&model), "--builtin", "glass-spheres", "-o", s(&d.join("x.exr"))]));
    assert!(e.contains("trained on another scene: built-in Cornell box") && e.contains("glass"), "{e}");
    // An edited header is refused by its checksum (issue 51: the header lay outside the
    // model's checksum, so a model claimed for seed 4 loaded). Injected bug checked:
    // without the checksum test in trained::load this render succeeds.
    let bytes = std::fs::read(&model).unwrap();
    let at = bytes.windows(8).position(|w| w == b"seed: 3\n").unwrap();
    let mut edited = bytes.clone();
    edited[at + 6] = b'4';
    let edited_path = d.join("edited.bin");
    std::fs::write(&edited_path, &edited).unwrap();
    let e = fails(&render(&["--model", s(&edited_path), "--seed", "4", "-o", s(&d.join("x.exr"))]));
    assert!(e.contains("edited.bin") && e.contains("header does not match its checksum"), "{e}");
    let e = fails(&ember(&["render", "--model", s(&model), "-o", s(&d.join("x.exr"))], &[]));
    assert!(e.contains("trained with estimator spcbpt, but this render has pt"), "{e}");
    let bytes = std::fs::read(&model).unwrap();
    let damaged = d.join("damaged.bin");
    std::fs::write(&damaged, &bytes[..bytes.len() - 100]).unwrap();
    let e = fails(&render(&["--model", s(&damaged), "-o", s(&d.join("x.exr"))]));
    assert!(e.contains("damaged.bin") && e.contains("checksum"), "{e}");
    let e = fails(&ember(&["train", "-e", "lvcbpt", "-o", s(&d.join("m.bin"))], &[]));
    assert!(e.contains("only spcbpt trains a model"), "{e}");
    let e = fails(&render(&["--model", s(&whole), "-o", s(&d.join("x.exr"))]));
    assert!(e.contains("is not a model file"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}
