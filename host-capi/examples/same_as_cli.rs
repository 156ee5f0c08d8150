//! Does `ember render` give the C example's image, bit for bit?
//!
//!     same_as_cli IMAGE.pfm render SCENE.xml [ember render's options] -o OUT.exr
//!
//! Runs the command line (the `ember` program's own code, in this process: parse, plan,
//! render, write), reads its EXR and the C example's PFM (`host-capi/c/scene2.c` writes
//! both that image and the scene as XML), prints how many pixels differ and the means,
//! and fails unless none does. Run by scripts/test-capi.sh; in-process, so the script
//! builds no `ember` binary of its own (a build of another feature set of the crates).

use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some((pfm, command)) = args.split_first() else {
        eprintln!("usage: same_as_cli IMAGE.pfm render SCENE.xml [options] -o OUT.exr");
        return ExitCode::from(2);
    };
    let Some(exr) = command.iter().position(|a| a == "-o").and_then(|i| command.get(i + 1)) else {
        eprintln!("same_as_cli: give the render's output with -o");
        return ExitCode::from(2);
    };
    let cli = match ember_cli::cli::Cli::try_parse_from(std::iter::once("ember").chain(command.iter().map(String::as_str))) {
        Ok(cli) => cli,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    };
    if let Err(e) = ember_cli::app::run(&cli, Instant::now()) {
        eprintln!("ember {}: {e}", command.join(" "));
        return ExitCode::FAILURE;
    }
    let a = match std::fs::read(pfm).map_err(|e| e.to_string()).and_then(|b| ember_formats::float_images::decode_pfm(&b)) {
        Ok(a) => a,
        Err(e) => {
            eprintln!("{pfm}: {e}");
            return ExitCode::FAILURE;
        }
    };
    let b = match ember_formats::image_io::read_exr(Path::new(exr)) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::FAILURE;
        }
    };
    if (a.width, a.height) != (b.width, b.height) {
        eprintln!("{pfm} is {}x{}, {exr} {}x{}", a.width, a.height, b.width, b.height);
        return ExitCode::FAILURE;
    }
    let mean = |p: &[[f32; 3]]| p.iter().flatten().map(|&x| x as f64).sum::<f64>() / (3 * p.len().max(1)) as f64;
    let differing = a.pixels.iter().zip(&b.pixels).filter(|(x, y)| x != y).count();
    println!(
        "ember {}: {differing} of {} pixels differ from {pfm} (means {:.6} and {:.6})",
        command.join(" "),
        a.pixels.len(),
        mean(&b.pixels),
        mean(&a.pixels)
    );
    if differing == 0 { ExitCode::SUCCESS } else { ExitCode::FAILURE }
}
