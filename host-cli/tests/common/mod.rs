//! Running `ember render` as a process and signalling it: shared by the signal tests
//! (`interrupt.rs`) and the resume tests (`resume.rs`).

use std::io::{BufRead, BufReader};
use std::process::{Child, ChildStderr, Command, Stdio};
use std::time::{Duration, Instant};

/// `ember` with `args`, stdout and stderr piped.
pub fn spawn(args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_ember")).args(args).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect("run ember")
}

/// Send the signal `name` (`INT`, `TERM`, …) to `child`.
pub fn signal(child: &Child, name: &str) {
    let ok = Command::new("kill").args([&format!("-{name}"), &child.id().to_string()]).status().expect("kill").success();
    assert!(ok, "kill -{name} failed");
}

/// Wait for `child`, then its exit status, the rest of stderr and stdout.
pub fn finish(mut child: Child, mut err: BufReader<ChildStderr>) -> (Option<i32>, String, String) {
    let status = child.wait().expect("wait");
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut err, &mut rest).unwrap();
    let mut stdout = String::new();
    std::io::Read::read_to_string(child.stdout.as_mut().unwrap(), &mut stdout).unwrap();
    (status.code(), rest, stdout)
}

/// Read stderr lines until one starts with `prefix` (the lines read so far returned).
pub fn wait_for(reader: &mut impl BufRead, prefix: &str) -> Vec<String> {
    let mut lines = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(60);
    while Instant::now() < deadline {
        let mut line = String::new();
        if reader.read_line(&mut line).expect("stderr") == 0 {
            break;
        }
        let done = line.starts_with(prefix);
        lines.push(line);
        if done {
            return lines;
        }
    }
    panic!("no line starting with {prefix:?}; stderr so far: {lines:?}");
}

/// The pass count in the closing line "interrupted by <by>: the image holds the N
/// completed passes" of `stderr`.
pub fn passes_held(stderr: &str, by: &str) -> u32 {
    let prefix = format!("interrupted by {by}: the image holds the ");
    stderr
        .lines()
        .find_map(|l| l.strip_prefix(prefix.as_str()).and_then(|t| t.split_whitespace().next()).and_then(|n| n.parse().ok()))
        .unwrap_or_else(|| panic!("no pass count in stderr: {stderr}"))
}
