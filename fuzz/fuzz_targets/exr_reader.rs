//! The EXR reader never panics (nor allocates without bound) on arbitrary bytes (issue 8):
//! it returns an image whose pixel count matches its size, or an error. Seeded with small
//! EXRs (`seeds/exr_reader/`).
#![no_main]

use ember_formats::image_io::read_exr_from_bytes;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(img) = read_exr_from_bytes(data) {
        assert_eq!(img.pixels.len(), img.width as usize * img.height as usize);
    }
});
