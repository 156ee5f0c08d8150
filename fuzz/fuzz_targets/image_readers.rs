//! The JPEG, Radiance RGBE and PFM readers never panic (nor allocate without bound) on
//! arbitrary bytes (issue 56): each returns texels whose count matches the size it
//! reports, or an error. The first byte picks the decoder (0 JPEG, 1 RGBE, 2 PFM, as
//! `seeds/image_readers/` are written); the rest is the file.
#![no_main]

use ember_formats::mitsuba::decode_image_bytes;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&pick, file)) = data.split_first() else { return };
    let extension = ["jpg", "hdr", "pfm"][pick as usize % 3];
    if let Ok((w, h, texels)) = decode_image_bytes(extension, file, pick & 0x80 != 0) {
        assert_eq!(texels.len(), w as usize * h as usize);
    }
});
