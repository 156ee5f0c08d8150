//! `ember-wasm-compare BROWSER.pfm NATIVE.exr [PIXEL_TOLERANCE]`: the browser test's verdict
//! (see `ember_wasm::compare`). Exit status 0 when the images agree, 1 when they do not,
//! 2 on a usage or file error.

#[cfg(not(target_arch = "wasm32"))]
fn main() {
    use std::path::Path;
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 2 || args.len() > 3 {
        eprintln!("usage: ember-wasm-compare BROWSER.pfm NATIVE.exr [PIXEL_TOLERANCE]");
        std::process::exit(2);
    }
    let tolerance = args.get(2).map_or(Ok(1e-5), |t| t.parse::<f64>()).unwrap_or_else(|_| {
        eprintln!("bad tolerance");
        std::process::exit(2)
    });
    let browser = std::fs::read(&args[0]).map_err(|e| e.to_string()).and_then(|b| ember_wasm::compare::parse_pfm(&b));
    let native = ember_cli::image_io::read_exr(Path::new(&args[1])).map_err(|e| e.to_string());
    let (browser, native) = match (browser, native) {
        (Ok(b), Ok(n)) => (b, ember_wasm::compare::LinearImage { width: n.width as usize, height: n.height as usize, pixels: n.pixels }),
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let verdict = ember_wasm::compare::compare(&browser, &native, ember_wasm::compare::Criteria { pixel_tolerance: tolerance, ..Default::default() });
    print!("{}", verdict.report);
    std::process::exit(if verdict.ok { 0 } else { 1 });
}

#[cfg(target_arch = "wasm32")]
fn main() {}
