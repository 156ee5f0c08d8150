//! Sets `EMBER_BUILD`: the git commit the program is built from, with `+dirty` when
//! tracked files differ from it ("unknown commit" outside a git checkout). Partial images
//! of split renders record it, and `ember merge` refuses parts from different builds.

use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    out.status.success().then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn main() {
    let build = match git(&["rev-parse", "--short=12", "HEAD"]) {
        Some(commit) => {
            let dirty = git(&["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty());
            format!("commit {commit}{}", if dirty { "+dirty" } else { "" })
        }
        None => "unknown commit".to_string(),
    };
    println!("cargo:rustc-env=EMBER_BUILD={build}");
    // A new commit or a change to the index (staging, committing) re-runs this script.
    for path in ["../.git/HEAD", "../.git/index"] {
        println!("cargo:rerun-if-changed={path}");
    }
}
