//! `ember render --aov albedo,normal`: the denoiser guides as extra EXR channels.
//!
//! On the built-in Cornell box (every surface diffuse and two-sided) the albedo guide of
//! a pixel on a wall is that wall's reflectance exactly, and its normal the wall's normal
//! facing the camera; the guides do not depend on the thread count.
//! Injected bug seen to fail this test: the normal taken as stored instead of facing the
//! ray (the back wall's triangles wind away from the camera: `normal.B` of pixel
//! (12, 10) read −1 instead of +1).

use std::path::Path;
use std::process::Command;

use ember_formats::image_io::read_exr_any;

/// Channel `name` of the EXR at `path`, as f32 samples.
fn channel(path: &Path, name: &str) -> Vec<f32> {
    let image = read_exr_any(path).expect("read the EXR");
    let layer = &image.layer_data[0];
    let c = layer.channel_data.list.iter().find(|c| c.name.to_string() == name).unwrap_or_else(|| panic!("no channel {name}"));
    match &c.sample_data {
        exr::image::FlatSamples::F32(v) => v.clone(),
        other => panic!("{name}: {other:?}"),
    }
}

#[test]
fn guides_are_written_and_independent_of_threads() {
    let dir = std::env::temp_dir().join(format!("ember-aov-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let run = |threads: &str, name: &str| {
        let out = dir.join(name);
        let o = Command::new(env!("CARGO_BIN_EXE_ember"))
            .args(["render", "--spp", "2", "--width", "32", "--height", "32", "--threads", threads, "--aov", "albedo,normal", "-o"])
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        out
    };
    let (a, b) = (run("1", "one.exr"), run("2", "two.exr"));
    for name in ["R", "albedo.R", "albedo.G", "albedo.B", "normal.R", "normal.G", "normal.B"] {
        assert_eq!(channel(&a, name), channel(&b, name), "{name} depends on the thread count");
    }
    // Pixel (12, 10) sees only the white back wall: albedo (0.725, 0.71, 0.68), normal
    // toward the camera (+z in the built-in box's frame, whose camera looks along −z).
    let centre = 10 * 32 + 12;
    let albedo = ["albedo.R", "albedo.G", "albedo.B"].map(|n| channel(&a, n)[centre]);
    assert!((albedo[0] - 0.725).abs() < 1e-5 && (albedo[1] - 0.71).abs() < 1e-5 && (albedo[2] - 0.68).abs() < 1e-5, "{albedo:?}");
    let normal = ["normal.R", "normal.G", "normal.B"].map(|n| channel(&a, n)[centre]);
    println!("centre normal {normal:?}");
    let len = (normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]).sqrt();
    assert!((len - 1.0).abs() < 1e-4 && normal[2] > 0.9999, "{normal:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
