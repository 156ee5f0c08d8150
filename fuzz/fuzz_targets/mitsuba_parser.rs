//! The Mitsuba scene reader never panics on arbitrary bytes (issue 8): invalid UTF-8 is
//! an error, and any text either loads or yields a `file:line:col` error. When a scene
//! loads, `SceneBuilder::build` must also return (a scene or a typed error) without
//! panicking. Seeded with the suite's scene files (`seeds/mitsuba_parser/`).
//!
//! Mesh paths resolve against a directory that does not exist, so inputs cannot make the
//! target read the machine's files.
#![no_main]

use std::path::Path;

use ember_formats::mitsuba::{LoadOptions, load_scene_from_str};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    // A film override keeps accidental huge resolutions from allocating at build time.
    let options = LoadOptions { width: Some(4), height: Some(4), ..LoadOptions::default() };
    match load_scene_from_str(text, Path::new("/nonexistent-ember-fuzz/scene.xml"), &options) {
        Ok(loaded) => {
            let _ = loaded.builder.build();
        }
        Err(e) => {
            let shown = e.to_string();
            assert!(shown.starts_with("/nonexistent-ember-fuzz/scene.xml"), "error does not name the file: {shown}");
        }
    }
});
