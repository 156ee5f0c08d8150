//! Image files: linear RGB float EXR (the renderer's output and the references'
//! format) and a tone-mapped 8-bit sRGB PNG for a quick look.
//!
//! Pixels are row-major `[r, g, b]` linear values, index `y·width + x`, y down.

use std::fmt;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// A linear RGB float image.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
}

/// What went wrong with which file.
#[derive(Debug)]
pub struct ImageError {
    pub path: PathBuf,
    pub kind: ImageErrorKind,
}

/// The cause of an [`ImageError`].
#[derive(Debug)]
pub enum ImageErrorKind {
    /// The exr crate failed to write or read (I/O errors included).
    Exr(exr::error::Error),
    /// The png crate failed to encode.
    Png(png::EncodingError),
    /// The file could not be created.
    Io(std::io::Error),
    /// The pixel buffer does not match the stated size.
    Size { width: u32, height: u32, pixels: usize },
    /// Pixels holding NaN or an infinity in some channel, where finite values are needed.
    NonFinite { count: usize, width: u32, height: u32 },
}

impl ImageError {
    pub fn new(path: &Path, kind: ImageErrorKind) -> Self {
        Self { path: path.to_path_buf(), kind }
    }
}

impl fmt::Display for ImageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = self.path.display();
        match &self.kind {
            ImageErrorKind::Exr(e) => write!(f, "EXR file '{p}': {e}"),
            ImageErrorKind::Png(e) => write!(f, "PNG file '{p}': {e}"),
            ImageErrorKind::Io(e) => write!(f, "could not create '{p}': {e}"),
            ImageErrorKind::Size { width, height, pixels } => {
                write!(f, "image for '{p}': {pixels} pixels given for {width}x{height}")
            }
            ImageErrorKind::NonFinite { count, width, height } => {
                write!(f, "image '{p}': {count} of its {width}x{height} pixels are not finite (NaN or infinite); the error metrics need finite values")
            }
        }
    }
}

impl std::error::Error for ImageError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match &self.kind {
            ImageErrorKind::Exr(e) => Some(e),
            ImageErrorKind::Png(e) => Some(e),
            ImageErrorKind::Io(e) => Some(e),
            ImageErrorKind::Size { .. } | ImageErrorKind::NonFinite { .. } => None,
        }
    }
}

fn check_size(path: &Path, width: u32, height: u32, pixels: &[[f32; 3]]) -> Result<(), ImageError> {
    if pixels.len() != width as usize * height as usize || width == 0 || height == 0 {
        return Err(ImageError::new(path, ImageErrorKind::Size { width, height, pixels: pixels.len() }));
    }
    Ok(())
}

/// Refuse an image (read from `path`) with a NaN or infinite channel anywhere, counting
/// the pixels that hold one.
pub fn check_finite(path: &Path, image: &RgbImage) -> Result<(), ImageError> {
    let count = image.pixels.iter().filter(|p| !p.iter().all(|c| c.is_finite())).count();
    if count > 0 {
        return Err(ImageError::new(path, ImageErrorKind::NonFinite { count, width: image.width, height: image.height }));
    }
    Ok(())
}

/// Write `path` atomically: `write` fills a temporary file beside it (same directory, so
/// the rename cannot cross file systems), which then replaces `path` in one rename. A
/// failed or interrupted write leaves the previous file as it was and no temporary file
/// behind.
pub fn write_atomically<E>(path: &Path, write: impl FnOnce(&Path) -> Result<(), E>, io_error: impl Fn(std::io::Error) -> E) -> Result<(), E> {
    let name = path.file_name().map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    let temp = path.with_file_name(format!(".{name}.{}.partial", std::process::id()));
    if let Err(e) = write(&temp) {
        let _ = std::fs::remove_file(&temp);
        return Err(e);
    }
    std::fs::rename(&temp, path).map_err(|e| {
        let _ = std::fs::remove_file(&temp);
        io_error(e)
    })
}

/// Write linear RGB as 32-bit float channels R, G, B (RLE compression, as the exr crate
/// defaults to). Values round-trip bit-exactly through [`read_exr`]. Chunks are
/// compressed on this thread, in order, so the same image gives the same bytes (the
/// crate's parallel writer stores chunks in completion order).
pub fn write_exr(path: &Path, width: u32, height: u32, pixels: &[[f32; 3]]) -> Result<(), ImageError> {
    use exr::prelude::*;
    check_size(path, width, height, pixels)?;
    let w = width as usize;
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let p = pixels[y * w + x];
        (p[0], p[1], p[2])
    });
    let image = Image::from_channels((w, height as usize), channels);
    write_atomically(
        path,
        |temp| image.write().non_parallel().to_file(temp).map_err(|e| ImageError::new(path, ImageErrorKind::Exr(e))),
        |e| ImageError::new(path, ImageErrorKind::Io(e)),
    )
}

/// [`write_exr`] with extra RGB images as channels `name.R`, `name.G`, `name.B` of the
/// same layer (the denoiser guides: `albedo`, `normal`), as renderers name AOVs.
pub fn write_exr_with(path: &Path, width: u32, height: u32, pixels: &[[f32; 3]], extra: &[(&str, &[[f32; 3]])]) -> Result<(), ImageError> {
    use exr::prelude::*;
    check_size(path, width, height, pixels)?;
    for (_, e) in extra {
        check_size(path, width, height, e)?;
    }
    let mut channels: Vec<AnyChannel<FlatSamples>> = Vec::new();
    let mut push = |prefix: &str, image: &[[f32; 3]]| {
        for (c, name) in ["R", "G", "B"].iter().enumerate() {
            channels.push(AnyChannel::new(format!("{prefix}{name}").as_str(), FlatSamples::F32(image.iter().map(|p| p[c]).collect())));
        }
    };
    push("", pixels);
    for (name, image) in extra {
        push(&format!("{name}."), image);
    }
    let layer = Layer::new((width as usize, height as usize), LayerAttributes::default(), Encoding::default(), AnyChannels::sort(channels.into()));
    let image = Image::from_layer(layer);
    write_atomically(
        path,
        |temp| image.write().non_parallel().to_file(temp).map_err(|e| ImageError::new(path, ImageErrorKind::Exr(e))),
        |e| ImageError::new(path, ImageErrorKind::Io(e)),
    )
}

/// Read the first layer with R, G and B channels of an EXR file as f32 (alpha, if any,
/// is dropped; half and uint channels are converted).
pub fn read_exr(path: &Path) -> Result<RgbImage, ImageError> {
    let fail = |e: exr::error::Error| ImageError::new(path, ImageErrorKind::Exr(e));
    let (file, len) = crate::files::open_regular(path).map_err(|e| fail(std::io::Error::other(e).into()))?;
    decode_exr(std::io::BufReader::new(file), len).map_err(fail)
}

/// Every layer, channel and attribute of an EXR file (the partial images of split
/// renders, `crate::distributed`), with the same header checks as [`read_exr`].
pub fn read_exr_any(path: &Path) -> Result<exr::image::FlatImage, ImageError> {
    let fail = |e: exr::error::Error| ImageError::new(path, ImageErrorKind::Exr(e));
    let (file, len) = crate::files::open_regular(path).map_err(|e| fail(std::io::Error::other(e).into()))?;
    decode_any(std::io::BufReader::new(file), len).map_err(fail)
}

/// [`read_exr_any`] on bytes in memory, errors naming `name` (the partial-image fuzz
/// target's entry point). Never panics on malformed input.
pub fn read_exr_any_from_bytes(name: &Path, bytes: &[u8]) -> Result<exr::image::FlatImage, ImageError> {
    decode_any(std::io::Cursor::new(bytes), bytes.len() as u64).map_err(|e| ImageError::new(name, ImageErrorKind::Exr(e)))
}

fn decode_any(mut reader: impl std::io::Read + std::io::Seek, len: u64) -> Result<exr::image::FlatImage, exr::error::Error> {
    use exr::prelude::*;
    check_exr_header(&mut reader, len)?;
    read().no_deep_data().largest_resolution_level().all_channels().all_layers().all_attributes().non_parallel().from_buffered(reader)
}

/// [`read_exr`] on bytes already in memory (the fuzz target's entry point); errors name
/// the file `<memory>`. Never panics on malformed input.
pub fn read_exr_from_bytes(bytes: &[u8]) -> Result<RgbImage, ImageError> {
    decode_exr(std::io::Cursor::new(bytes), bytes.len() as u64).map_err(|e| ImageError::new(Path::new("<memory>"), ImageErrorKind::Exr(e)))
}

/// The most pixels an EXR may declare (64 Mpixel, 768 MiB as f32 RGB, past any reference
/// image here): a corrupt or hostile header must not make the reader allocate without bound.
const MAX_EXR_PIXELS: usize = 1 << 26;

/// Largest expansion of any compression the reader supports (deflate's ≈ 1032:1 in ZIP
/// and PXR24, PIZ's Huffman runs ≈ 450:1, RLE 64:1, B44 ≈ 11:1), with margin.
const MAX_EXR_EXPANSION: u64 = 4096;

/// Reject, from the header alone, a file whose declared layout cannot fit in its
/// `file_len` bytes: every chunk has an 8-byte entry in the offset table, and no
/// compression expands its data more than [`MAX_EXR_EXPANSION`] times, so a header
/// declaring more chunks, or more pixel bytes, than that is corrupt or hostile (the
/// fuzzer's 397-byte files declaring 134 M pixels, or one 60 M-pixel scanline, made the
/// reader allocate up to 2.3 GB before noticing). Also bounds the pixel count by
/// [`MAX_EXR_PIXELS`].
fn check_exr_header(reader: &mut (impl std::io::Read + std::io::Seek), file_len: u64) -> Result<(), exr::error::Error> {
    use exr::error::Error;
    let start = reader.stream_position()?;
    let meta = exr::meta::MetaData::read_from_buffered(&mut *reader, false)?;
    reader.seek(std::io::SeekFrom::Start(start))?;
    let mut chunks: u64 = 0;
    for header in meta.headers.iter() {
        let size = header.layer_size;
        if size.width().checked_mul(size.height()).is_none_or(|n| n > MAX_EXR_PIXELS) {
            return Err(Error::NotSupported(format!("a {}x{} layer (more than {} pixels)", size.width(), size.height(), MAX_EXR_PIXELS).into()));
        }
        chunks = chunks.saturating_add(header.chunk_count as u64);
        let bytes = (size.width() as u64 * size.height() as u64).saturating_mul(header.channels.bytes_per_pixel as u64);
        if bytes > file_len.saturating_mul(MAX_EXR_EXPANSION) {
            return Err(Error::Invalid(
                format!("a {}x{} layer of {bytes} bytes cannot be stored in a {file_len}-byte file", size.width(), size.height()).into(),
            ));
        }
    }
    if chunks.saturating_mul(8) > file_len {
        return Err(Error::Invalid(format!("the header declares {chunks} chunks, more than a {file_len}-byte file can index").into()));
    }
    Ok(())
}

fn decode_exr(mut reader: impl std::io::Read + std::io::Seek, file_len: u64) -> Result<RgbImage, exr::error::Error> {
    use exr::prelude::*;
    check_exr_header(&mut reader, file_len)?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |size, _| {
                // Reading stops at the first pixel of an oversized image (see below).
                let n = size.width().checked_mul(size.height()).filter(|&n| n <= MAX_EXR_PIXELS).unwrap_or(0);
                (size.width(), vec![[0.0f32; 3]; n])
            },
            |(w, px): &mut (usize, Vec<[f32; 3]>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                if let Some(p) = px.get_mut(pos.y() * *w + pos.x()) {
                    *p = [r, g, b];
                }
            },
        )
        .first_valid_layer()
        .all_attributes()
        // Decode on this thread: the result does not depend on scheduling, and a fault in
        // a decoder surfaces here, with its input, instead of in a pool thread.
        .non_parallel()
        .from_buffered(reader)?;
    let size = image.layer_data.size;
    let (_, pixels) = image.layer_data.channel_data.pixels;
    if pixels.len() != size.width() * size.height() {
        return Err(exr::error::Error::NotSupported("images larger than 2^26 pixels".into()));
    }
    Ok(RgbImage { width: size.width() as u32, height: size.height() as u32, pixels })
}

/// The sRGB transfer function (IEC 61966-2-1) of a linear value, clamped to [0, 1] and
/// quantised to 8 bits with rounding. NaN maps to 0.
pub fn srgb_encode(linear: f32) -> u8 {
    let v = if linear.is_nan() { 0.0 } else { linear.clamp(0.0, 1.0) };
    let e = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (e * 255.0 + 0.5).clamp(0.0, 255.0) as u8
}

/// Write an 8-bit sRGB PNG (tagged sRGB): each linear value is multiplied by
/// 2^`exposure` (stops), clamped to [0, 1] and sRGB-encoded.
pub fn write_png(path: &Path, width: u32, height: u32, pixels: &[[f32; 3]], exposure: f32) -> Result<(), ImageError> {
    check_size(path, width, height, pixels)?;
    let scale = exposure.exp2();
    let bytes: Vec<u8> = pixels.iter().flat_map(|p| p.map(|v| srgb_encode(v * scale))).collect();
    write_atomically(
        path,
        |temp| {
            let file = File::create(temp).map_err(|e| ImageError::new(path, ImageErrorKind::Io(e)))?;
            let mut encoder = png::Encoder::new(BufWriter::new(file), width, height);
            encoder.set_color(png::ColorType::Rgb);
            encoder.set_depth(png::BitDepth::Eight);
            encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
            let png_err = |e| ImageError::new(path, ImageErrorKind::Png(e));
            let mut writer = encoder.write_header().map_err(png_err)?;
            writer.write_image_data(&bytes).map_err(png_err)?;
            writer.finish().map_err(png_err)
        },
        |e| ImageError::new(path, ImageErrorKind::Io(e)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("ember-formats-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join(name)
    }

    /// A write that fails half-way (the closure writes garbage, then errs) keeps the old
    /// file byte for byte and leaves no temporary file. Seen failing with the closure
    /// writing to `path` itself (no temporary file).
    #[test]
    fn a_failed_write_keeps_the_old_file() {
        let path = temp("atomic.exr");
        write_exr(&path, 2, 1, &[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]).unwrap();
        let before = std::fs::read(&path).unwrap();
        let r: Result<(), String> = write_atomically(
            &path,
            |temp| {
                std::fs::write(temp, b"half an image").unwrap();
                Err("disk full".into())
            },
            |e| e.to_string(),
        );
        assert_eq!(r, Err("disk full".into()));
        assert_eq!(std::fs::read(&path).unwrap(), before, "the old file is intact");
        let leftovers: Vec<_> = std::fs::read_dir(path.parent().unwrap())
            .unwrap()
            .filter_map(|e| e.ok())
            // Its own only: other tests write atomically into the same directory at the
            // same time (seen failing on `det_a.exr`'s temporary file once this module's
            // tests ran in a smaller binary).
            .filter(|e| e.file_name().to_string_lossy().starts_with(".atomic.exr.") && e.file_name().to_string_lossy().ends_with(".partial"))
            .collect();
        assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
        // A successful write replaces it.
        write_exr(&path, 1, 1, &[[7.0, 8.0, 9.0]]).unwrap();
        assert_eq!(read_exr(&path).unwrap().pixels, vec![[7.0, 8.0, 9.0]]);
    }

    #[test]
    fn exr_round_trip_is_bit_exact() {
        let (w, h) = (37u32, 11u32);
        let pixels: Vec<[f32; 3]> = (0..w * h)
            .map(|i| {
                let x = i as f32;
                [x * 0.123_456_7, (x * 1.7).sin().abs() * 1e6, f32::from_bits(0x0000_0001 + i)]
            })
            .collect();
        let path = temp("round-trip.exr");
        write_exr(&path, w, h, &pixels).unwrap();
        let back = read_exr(&path).unwrap();
        assert_eq!((back.width, back.height), (w, h));
        let bits = |p: &[[f32; 3]]| p.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back.pixels), bits(&pixels));
        std::fs::remove_file(&path).ok();
    }

    #[test]
    fn png_writes_srgb_bytes() {
        let path = temp("tone.png");
        let pixels = [[0.0, 0.5, 1.0], [2.0, f32::NAN, 0.001], [0.2, 0.0, 0.0], [0.25, 0.25, 0.25]];
        write_png(&path, 2, 2, &pixels, 0.0).unwrap();
        let decoder = png::Decoder::new(std::io::BufReader::new(File::open(&path).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height, info.color_type), (2, 2, png::ColorType::Rgb));
        assert_eq!(&buf[..12], &[0, 188, 255, 255, 0, 3, 124, 0, 0, 137, 137, 137]);
        // One stop of exposure doubles before encoding.
        write_png(&path, 2, 2, &pixels, 1.0).unwrap();
        let mut reader = png::Decoder::new(std::io::BufReader::new(File::open(&path).unwrap())).read_info().unwrap();
        reader.next_frame(&mut buf).unwrap();
        assert_eq!(&buf[9..12], &[188, 188, 188]);
        std::fs::remove_file(&path).ok();
    }

    #[test]
    fn errors_name_the_file() {
        let bad = Path::new("/nonexistent-dir-for-ember/x.exr");
        let e = write_exr(bad, 1, 1, &[[0.0; 3]]).unwrap_err();
        assert!(e.to_string().contains("/nonexistent-dir-for-ember/x.exr"), "{e}");
        let e = write_png(Path::new("/nonexistent-dir-for-ember/x.png"), 1, 1, &[[0.0; 3]], 0.0).unwrap_err();
        assert!(e.to_string().contains("x.png"), "{e}");
        let e = read_exr(Path::new("/nonexistent-dir-for-ember/y.exr")).unwrap_err();
        assert!(e.to_string().contains("y.exr"), "{e}");
        let e = write_exr(Path::new("z.exr"), 2, 2, &[[0.0; 3]]).unwrap_err();
        assert!(matches!(e.kind, ImageErrorKind::Size { .. }) && e.to_string().contains("z.exr"));
    }

    /// The fuzz target's seeds (hand-written uncompressed EXRs, float and half) decode;
    /// every truncation of them is an error, never a panic; a header declaring 2³² pixels
    /// is refused before anything that size is allocated.
    #[test]
    fn in_memory_reader_decodes_seeds_and_rejects_damage() {
        let seeds = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/seeds/exr_reader");
        let float = std::fs::read(seeds.join("float_2x2.exr")).unwrap();
        let img = read_exr_from_bytes(&float).unwrap();
        assert_eq!((img.width, img.height), (2, 2));
        assert_eq!(img.pixels[1], [1.5 + 2.0, 1.5 + 1.0, 1.5]); // channels stored B, G, R
        let half = std::fs::read(seeds.join("half_3x2.exr")).unwrap();
        assert_eq!(read_exr_from_bytes(&half).unwrap().pixels.len(), 6);
        for n in 0..float.len() {
            assert!(read_exr_from_bytes(&float[..n]).is_err(), "truncated to {n} bytes");
        }
        // dataWindow (0, 0)–(65535, 65535): patch the box2i of the float seed.
        let at = float.windows(10).position(|w| w == b"dataWindow").unwrap() + b"dataWindow\0box2i\0".len() + 4;
        let mut huge = float.clone();
        huge[at + 8..at + 16].copy_from_slice(&[0xff, 0xff, 0, 0, 0xff, 0xff, 0, 0]);
        assert!(read_exr_from_bytes(&huge).is_err());
    }

    /// Fuzz finding (CI, exr_reader): a 397-byte file whose dataWindow declares a
    /// 67108865×2 layer made the reader allocate its 1.6 GB pixel buffer (then the bound
    /// was 2^28 pixels) and libFuzzer stopped at 2.3 GB. Both header checks must refuse
    /// such files before anything is allocated: the pixel bound (this seed), and the
    /// chunk table (a 1×4096 layer of the float seed: few pixels, too many chunks), and the
    /// expansion bound. Seen failing with `check_exr_header` removed from `decode_exr`.
    #[test]
    fn oversized_headers_are_refused_before_decoding() {
        let seeds = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/seeds/exr_reader");
        let bytes = std::fs::read(seeds.join("header_declares_huge_layer.exr")).unwrap();
        let message = read_exr_from_bytes(&bytes).unwrap_err().to_string();
        assert!(message.contains("a 67108865x2 layer (more than 67108864 pixels)"), "{message}");

        let mut tall = std::fs::read(seeds.join("float_2x2.exr")).unwrap();
        let at = tall.windows(10).position(|w| w == b"dataWindow").unwrap() + b"dataWindow\0box2i\0".len() + 4;
        tall[at..at + 16].copy_from_slice(&[0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xff, 0x0f, 0, 0]);
        let message = read_exr_from_bytes(&tall).unwrap_err().to_string();
        assert!(message.contains("declares 4096 chunks"), "{message}");

        // One scanline of 2^24 pixels: one chunk, but 192 MiB of float RGB from a
        // 300-byte file (the fuzzer's slow inputs after the two checks above).
        let mut wide = std::fs::read(seeds.join("float_2x2.exr")).unwrap();
        wide[at..at + 16].copy_from_slice(&[0, 0, 0, 0, 0, 0, 0, 0, 0xff, 0xff, 0xff, 0, 0, 0, 0, 0]);
        let message = read_exr_from_bytes(&wide).unwrap_err().to_string();
        assert!(message.contains("a 16777216x1 layer of 201326592 bytes cannot be stored"), "{message}");
    }

    /// The same image written twice gives the same bytes (determinism of the output
    /// files, not only of the pixels). Seen failing with the crate's parallel writer
    /// (`.non_parallel()` removed): chunks land in completion order.
    #[test]
    fn exr_bytes_are_deterministic() {
        let (w, h) = (512u32, 384u32);
        let pixels: Vec<[f32; 3]> = (0..w * h).map(|i| [(i % 97) as f32 * 0.37, (i % 13) as f32, (i / 7) as f32 * 1e-3]).collect();
        let (a, b) = (temp("det_a.exr"), temp("det_b.exr"));
        write_exr(&a, w, h, &pixels).unwrap();
        write_exr(&b, w, h, &pixels).unwrap();
        assert!(std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(), "two writes of one image differ");
    }
}
