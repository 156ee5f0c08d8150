//! Are two images the same bits? `same_image C.pfm CLI.exr`: the C example's image (PFM,
//! as `host-capi/c/scene2.c` writes it) against `ember render`'s (EXR) of the same scene
//! in XML; prints how many pixels differ and the images' means, and fails unless none
//! does. Run by scripts/test-capi.sh.

use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [pfm, exr] = &args[..] else {
        eprintln!("usage: same_image IMAGE.pfm IMAGE.exr");
        return ExitCode::from(2);
    };
    let a = match std::fs::read(pfm).map_err(|e| e.to_string()).and_then(|b| ember_formats::float_images::decode_pfm(&b)) {
        Ok(a) => a,
        Err(e) => {
            eprintln!("{pfm}: {e}");
            return ExitCode::FAILURE;
        }
    };
    let b = match ember_formats::image_io::read_exr(std::path::Path::new(exr)) {
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
    println!("{differing} of {} pixels differ (means {:.6} and {:.6})", a.pixels.len(), mean(&a.pixels), mean(&b.pixels));
    if differing == 0 { ExitCode::SUCCESS } else { ExitCode::FAILURE }
}
