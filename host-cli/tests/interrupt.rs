//! Ctrl-C on a real process: a real SIGINT to a running `ember render`.
//!
//! - The first keeps the completed passes: the pass in progress is finished, the EXR
//!   holds exactly the passes the summary reports, and the exit status is 130.
//! - A second one quits at once without writing anything.
//!
//! Seen failing with the handler not installed (the default SIGINT action: status
//! `None`, killed by the signal, no image), and with the driver not polling the flag
//! (the first test waits out its 60 s limit).
#![cfg(unix)]

mod common;

use std::io::BufReader;
use std::path::Path;
use std::process::{Child, Command};
use std::time::{Duration, Instant};

use common::{finish, passes_held, signal, spawn, wait_for};

fn sigint(child: &Child) {
    signal(child, "INT");
}

/// The pass count in the closing line "interrupted by <signal>: the image holds the N
/// completed passes", checked against the summary on stdout and the image's validity.
fn passes_written(rest: &str, stdout: &str, by: &str, out: &Path) -> u32 {
    let passes = passes_held(rest, by);
    assert!(passes >= 1, "{rest}");
    assert!(stdout.contains(&format!("passes     {passes} ")), "the summary reports another count: {stdout}");
    let image = ember_formats::image_io::read_exr(out).expect("a valid image");
    assert!(image.pixels.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
    assert!(image.pixels.iter().flatten().sum::<f32>() > 0.0, "a black image");
    passes
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("ember-interrupt-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

#[test]
fn the_first_ctrl_c_writes_the_completed_passes() {
    let dir = temp_dir("first");
    let out = dir.join("out.exr");
    let mut child = spawn(&["render", "--width", "32", "--height", "32", "--spp", "10000000", "--time", "60", "--threads", "2", "-o", out.to_str().unwrap()]);
    let mut err = BufReader::new(child.stderr.take().unwrap());
    wait_for(&mut err, "progress: 1 pass");
    sigint(&child);
    let (status, rest, stdout) = finish(child, err);
    assert_eq!(status, Some(130), "exit status; stderr: {rest}");
    passes_written(&rest, &stdout, "Ctrl-C", &out);
    let image = ember_formats::image_io::read_exr(&out).expect("a valid image");
    assert_eq!((image.width, image.height), (32, 32));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_second_ctrl_c_quits_without_writing() {
    let dir = temp_dir("second");
    let out = dir.join("out.exr");
    // Passes of about three seconds each (BDPT at 1000×1000 on 2 threads), so both
    // signals land in the second pass.
    let mut child = spawn(&["render", "-e", "bdpt", "--width", "1000", "--height", "1000", "--spp", "1000", "--threads", "2", "-o", out.to_str().unwrap()]);
    let mut err = BufReader::new(child.stderr.take().unwrap());
    // After the first pass, not merely after "render:": a signal before pass 0 begins
    // ends the render at once with nothing to finish, and the second signal then finds
    // the process gone (seen once in CI: "0 passes at 0.0 s", exit status not 130).
    wait_for(&mut err, "progress: 1 pass");
    sigint(&child);
    wait_for(&mut err, "interrupt: finishing");
    // Past the 100 ms in which repeats count as the same Ctrl-C (GNU timeout's double
    // delivery), and within the pass (about 3 s at 1000×1000).
    std::thread::sleep(Duration::from_millis(1000));
    let sent = Instant::now();
    sigint(&child);
    let status = child.wait().expect("wait");
    let quit = sent.elapsed();
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut err, &mut rest).unwrap();
    assert_eq!(status.code(), Some(130), "exit status; stderr: {rest}");
    assert!(rest.contains("quitting"), "{rest}");
    assert!(!Path::new(&out).exists(), "an image was written");
    assert!(quit < Duration::from_secs(2), "took {quit:?} to quit");
    let _ = std::fs::remove_dir_all(&dir);
}

/// SIGTERM (a scheduler's time limit, `docker stop`, Kubernetes' eviction) and SIGHUP
/// write the completed passes within the grace of two seconds plus the write, abandoning
/// a longer pass in progress, and exit with 128 + the signal (issue 50: both lost the
/// whole render). Injected bugs checked: without SIGTERM among the handled signals the
/// status is `None` (killed) and nothing is written; without `abandon_pass` polled in the
/// driver the SIGTERM run takes its whole pass of about 4 s.
#[test]
fn termination_signals_write_the_completed_passes_at_once() {
    for (name, by, code, size) in [("TERM", "SIGTERM", 143, "900"), ("HUP", "SIGHUP", 129, "64")] {
        let dir = temp_dir(&format!("term-{name}"));
        let out = dir.join("out.exr");
        // SIGTERM: passes of about 4 s (BDPT at 900×900 on 2 threads, unloaded), longer than the
        // grace; SIGHUP: short passes.
        let mut child = spawn(&["render", "-e", "bdpt", "--width", size, "--height", size, "--spp", "100000", "--threads", "2", "-o", out.to_str().unwrap()]);
        let mut err = BufReader::new(child.stderr.take().unwrap());
        // From "render:" (the scene loaded and planned) to the first pass: about one pass
        // (BDPT's setup takes milliseconds), as long as the second will take.
        wait_for(&mut err, "render:");
        let started = Instant::now();
        wait_for(&mut err, "progress: 1 pass");
        let pass = started.elapsed();
        let sent = Instant::now();
        signal(&child, name);
        // A repeat must not abort the write.
        std::thread::sleep(Duration::from_millis(300));
        let _ = Command::new("kill").args([&format!("-{name}"), &child.id().to_string()]).status();
        let (status, rest, stdout) = finish(child, err);
        let took = sent.elapsed();
        eprintln!("{by}: exited {took:?} after the signal, passes of {pass:?}");
        assert_eq!(status, Some(code), "exit status; stderr: {rest}");
        passes_written(&rest, &stdout, by, &out);
        // Abandoned at the grace (2 s) plus the write, before the pass could end; where
        // the machine is fast enough that the pass ends within the grace, that is right too.
        if name == "TERM" && pass > Duration::from_millis(3500) {
            assert!(took < pass - Duration::from_millis(500), "took {took:?} with passes of {pass:?}: the pass in progress was not abandoned");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// Two SIGINTs back to back, and GNU `timeout -s INT` (which signals the child and then
/// its process group, so it arrives twice), are one Ctrl-C: the completed passes are
/// written (issue 50: two back-to-back `kill -INT` lost the image in 2 of 3 tries).
/// Injected bug checked: with `REPEAT_WINDOW` at zero, the first case exits "quitting;
/// nothing written".
#[test]
fn a_doubled_ctrl_c_is_one() {
    let dir = temp_dir("double");
    let out = dir.join("out.exr");
    let mut child = spawn(&["render", "--width", "64", "--height", "64", "--spp", "10000000", "--time", "60", "--threads", "2", "-o", out.to_str().unwrap()]);
    let mut err = BufReader::new(child.stderr.take().unwrap());
    wait_for(&mut err, "progress: 1 pass");
    let pid = child.id().to_string();
    let ok = Command::new("sh").args(["-c", &format!("kill -INT {pid}; kill -INT {pid}")]).status().expect("sh").success();
    assert!(ok);
    let (status, rest, stdout) = finish(child, err);
    assert_eq!(status, Some(130), "exit status; stderr: {rest}");
    passes_written(&rest, &stdout, "Ctrl-C", &out);

    let timed = dir.join("timed.exr");
    let o = Command::new("timeout")
        .args([
            "--preserve-status",
            "-s",
            "INT",
            "2",
            env!("CARGO_BIN_EXE_ember"),
            "render",
            "--width",
            "64",
            "--height",
            "64",
            "--spp",
            "10000000",
            "--threads",
            "2",
            "-o",
        ])
        .arg(&timed)
        .output()
        .expect("timeout");
    let rest = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "exit status; stderr: {rest}");
    passes_written(&rest, &String::from_utf8_lossy(&o.stdout), "Ctrl-C", &timed);
    let _ = std::fs::remove_dir_all(&dir);
}
