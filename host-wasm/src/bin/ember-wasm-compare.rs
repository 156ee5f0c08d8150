//! `ember-wasm-compare BROWSER.pfm NATIVE.exr [PIXEL_TOLERANCE]`: the browser test's
//! verdict for a render with the native one's seed (see `ember_wasm::compare`).
//!
//! `ember-wasm-compare BROWSER.pfm independent NATIVE1.exr NATIVE2.exr NATIVE3.exr ...`:
//! the verdict for a browser render with a seed of its own against three or more native
//! renders with seeds of theirs (`compare_independent`: a per-block t-test).
//!
//! Exit status 0 when the images agree, 1 when they do not, 2 on a usage or file error.
//!
//! `ember-wasm-compare --estimators`: the core's estimator list, one name per line (what
//! the page offers; the browser test iterates it).

#[cfg(not(target_arch = "wasm32"))]
fn main() {
    use std::path::Path;
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() == 1 && args[0] == "--estimators" {
        for kind in ember_core::estimators::EstimatorKind::ALL {
            println!("{}", kind.name());
        }
        return;
    }
    let usage = || -> ! {
        eprintln!(
            "usage: ember-wasm-compare BROWSER.pfm NATIVE.exr [PIXEL_TOLERANCE]\n       ember-wasm-compare BROWSER.pfm independent NATIVE1.exr NATIVE2.exr NATIVE3.exr ...\n       ember-wasm-compare --estimators"
        );
        std::process::exit(2)
    };
    let read_native = |p: &String| {
        ember_formats::image_io::read_exr(Path::new(p))
            .map(|n| ember_wasm::compare::LinearImage { width: n.width as usize, height: n.height as usize, pixels: n.pixels })
            .unwrap_or_else(|e| {
                eprintln!("error: {p}: {e}");
                std::process::exit(2)
            })
    };
    if args.len() < 2 {
        usage();
    }
    let browser = std::fs::read(&args[0]).map_err(|e| e.to_string()).and_then(|b| ember_wasm::compare::parse_pfm(&b)).unwrap_or_else(|e| {
        eprintln!("error: {}: {e}", args[0]);
        std::process::exit(2)
    });
    let criteria = ember_wasm::compare::Criteria::default();
    let verdict = if args[1] == "independent" {
        if args.len() < 5 {
            usage();
        }
        let natives: Vec<_> = args[2..].iter().map(read_native).collect();
        ember_wasm::compare::compare_independent(&browser, &natives, criteria)
    } else {
        if args.len() > 3 {
            usage();
        }
        let pixel_tolerance = match args.get(2).map(|t| t.parse::<f64>()) {
            None => criteria.pixel_tolerance,
            Some(Ok(t)) if t >= 0.0 => t,
            Some(_) => {
                eprintln!("bad tolerance {:?}: a non-negative number", args[2]);
                std::process::exit(2)
            }
        };
        ember_wasm::compare::compare(&browser, &read_native(&args[1]), ember_wasm::compare::Criteria { pixel_tolerance, ..criteria })
    };
    print!("{}", verdict.report);
    std::process::exit(if verdict.ok { 0 } else { 1 });
}

#[cfg(target_arch = "wasm32")]
fn main() {}
