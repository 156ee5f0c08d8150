//! The partial-image reader of split renders (`host-cli/src/distributed.rs`, issue 22)
//! never panics on arbitrary bytes (a part copied from another machine may be damaged),
//! and what it accepts is consistent: the film holds the header's pass count and size.
//! Seeded with small partial images `ember render --passes` wrote (`seeds/partial_reader/`).
#![no_main]

use std::path::Path;

use ember_cli::distributed::read_partial_from_bytes;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok((header, film)) = read_partial_from_bytes(Path::new("fuzz.exr"), data) {
        assert_eq!(film.passes(), header.passes.len());
        assert_eq!((film.width(), film.height()), (header.width, header.height));
        assert!(header.passes.end <= header.total);
        let _ = film.to_rgb_f32();
    }
});
