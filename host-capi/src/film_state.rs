//! A film's state as bytes, for `ember_film_export` and `ember_film_import`: what an
//! engine saves to continue a render later, in this process or another.
//!
//! A continued render is the split render of passes `N..` into a fresh film (the
//! driver's `first_pass`, which makes SPCBPT replay passes `0..N` first), merged with the
//! imported film by [`Film::merge`]: the film's sums are exact integers, so the result is
//! bit-identical to one uninterrupted render, as `ember render --resume` promises
//! (docs/reliability.md). That promise needs the same passes: the bytes carry what they
//! depend on ([`FilmIdentity`]) and an import refuses a film of another render.
//!
//! # Format, version 2 (integers little-endian)
//! | bytes | field |
//! |---|---|
//! | 8 | magic `EMBRFILM` |
//! | 4 | format version (2; version 1, before issue 52, had no film kind) |
//! | 4, 4 | width, height |
//! | 4 | passes (the film holds passes `0..passes`) |
//! | 8, 8, 8 | tallies: discarded, splats outside, saturated |
//! | 8 | seed |
//! | 4 | max depth (i32, −1 unbounded) |
//! | 4 | tracer: 0 the built-in BVH, 1 the engine's callbacks |
//! | 4 | film kind: 0 the box filter's sums alone, 1 also a tent's or gaussian's weighted sums |
//! | 8 | scene hash ([`crate::SceneData::hash`]) |
//! | 2 + n, 2 + n, 2 + n | ember build, estimator name, configuration: u16 length + UTF-8 |
//! | 48 × width × height | the exact sums, u128 per channel, pixels in row order |
//! | 64 × width × height | film kind 1 only: the camera samples' weighted sums Σ f L (u128 per channel) and Σ f (u128), pixels in row order (`Film::weighted_sums`) |
//! | 8 | checksum: FNV-1a 64 of every byte before it |
//!
//! Every length is checked before it is used: the size the header implies must equal the
//! buffer's, so a truncated or extended buffer is refused before anything is allocated
//! from a damaged width or height.

use ember_core::fnv::fnv1a;
use ember_core::render::{Film, Tallies, WeightedSum};

use crate::{EmberStatus, Error, Result};

/// The first bytes of every exported film.
const MAGIC: [u8; 8] = *b"EMBRFILM";
/// The format version this library writes and reads.
const FORMAT_VERSION: u32 = 2;
/// Bytes per pixel: three u128 sums.
const PIXEL_BYTES: usize = 3 * 16;
/// Bytes per pixel of a weighted film's weighted sums: four u128.
const WEIGHTED_BYTES: usize = 4 * 16;
/// Bytes of the fixed part of the header (magic through film kind).
const FIXED: usize = 8 + 4 + 4 + 4 + 4 + 3 * 8 + 8 + 4 + 4 + 8 + 4;
const CHECKSUM: usize = 8;

/// What a film's passes depend on besides their indices: two films continue each other
/// only when every field is equal.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FilmIdentity {
    /// `ember_version()`: another build may render other bits.
    pub build: String,
    pub estimator: String,
    /// The estimator's configuration and the shared settings but seed and depth, as text.
    pub config: String,
    pub seed: u64,
    pub max_depth: i32,
    /// The engine's callbacks (true) or the built-in BVH: two tracers round differently.
    pub callbacks: bool,
    pub scene_hash: u64,
    pub width: u32,
    pub height: u32,
    /// The film keeps its camera samples' weighted sums (a tent or gaussian filter).
    pub weighted: bool,
}

impl FilmIdentity {
    /// The strings, in the order they are stored.
    fn strings(&self) -> [&str; 3] {
        [&self.build, &self.estimator, &self.config]
    }

    /// The first field in which `film` (read from bytes) differs from `self` (the
    /// renderer's), in words.
    fn mismatch(&self, film: &Self) -> Option<String> {
        let tracer = |callbacks: bool| if callbacks { "the engine's callbacks" } else { "the built-in BVH" };
        let depth = |d: i32| if d < 0 { "unbounded".to_string() } else { d.to_string() };
        let kind = |weighted: bool| if weighted { "weighted (tent or gaussian filter)" } else { "box filter" };
        let fields = [
            ("ember build", film.build.clone(), self.build.clone()),
            ("estimator", film.estimator.clone(), self.estimator.clone()),
            ("configuration", film.config.clone(), self.config.clone()),
            ("seed", film.seed.to_string(), self.seed.to_string()),
            ("max depth", depth(film.max_depth), depth(self.max_depth)),
            ("tracer", tracer(film.callbacks).into(), tracer(self.callbacks).into()),
            ("size", format!("{}x{}", film.width, film.height), format!("{}x{}", self.width, self.height)),
            ("scene", format!("hash {:016x}", film.scene_hash), format!("hash {:016x}", self.scene_hash)),
            ("film kind", kind(film.weighted).into(), kind(self.weighted).into()),
        ];
        fields
            .into_iter()
            .find(|(_, a, b)| a != b)
            .map(|(name, a, b)| format!("{name}: the film's is {a}, this renderer's {b} (a film continues only the render it came from)"))
    }
}

/// The bytes [`encode`] writes for `identity`'s film, or `None` when they would not fit a
/// `usize` (or a string is past a u16 length, which no identity this library makes is).
pub fn encoded_len(identity: &FilmIdentity) -> Option<usize> {
    let pixels = (identity.width as usize).checked_mul(identity.height as usize)?;
    let per_pixel = PIXEL_BYTES + if identity.weighted { WEIGHTED_BYTES } else { 0 };
    let mut n = FIXED.checked_add(pixels.checked_mul(per_pixel)?)?.checked_add(CHECKSUM)?;
    for s in identity.strings() {
        u16::try_from(s.len()).ok()?;
        n = n.checked_add(2 + s.len())?;
    }
    Some(n)
}

/// Write `film`, of the render `identity` names, into `out`, which holds exactly
/// [`encoded_len`] bytes.
///
/// # Panics
/// If `out` is not that size or the film is not `identity`'s size (the caller's checks).
pub fn encode(identity: &FilmIdentity, film: &Film, out: &mut [u8]) {
    assert_eq!(Some(out.len()), encoded_len(identity), "the caller sizes the buffer");
    assert_eq!((film.width(), film.height()), (identity.width, identity.height), "the identity is the film's");
    assert_eq!(!film.weighted_sums().is_empty(), identity.weighted, "the identity is the film's");
    let mut w = Writer { out, at: 0 };
    w.put(&MAGIC);
    w.put(&FORMAT_VERSION.to_le_bytes());
    for v in [identity.width, identity.height, film.passes()] {
        w.put(&v.to_le_bytes());
    }
    let t = film.tallies();
    for v in [t.discarded, t.splats_outside, t.saturated, identity.seed] {
        w.put(&v.to_le_bytes());
    }
    w.put(&identity.max_depth.to_le_bytes());
    w.put(&u32::from(identity.callbacks).to_le_bytes());
    w.put(&identity.scene_hash.to_le_bytes());
    w.put(&u32::from(identity.weighted).to_le_bytes());
    for s in identity.strings() {
        w.put(&(s.len() as u16).to_le_bytes());
        w.put(s.as_bytes());
    }
    for sum in film.exact_sums() {
        for c in sum {
            w.put(&c.to_le_bytes());
        }
    }
    for s in film.weighted_sums() {
        for c in s.value.iter().chain([&s.weight]) {
            w.put(&c.to_le_bytes());
        }
    }
    let end = w.at;
    let checksum = fnv1a(&w.out[..end]);
    w.put(&checksum.to_le_bytes());
}

/// The film `bytes` hold, checked to be a film of the render `this` names: magic, format
/// version, size, checksum, then every field of the identity. Errors are
/// `EMBER_STATUS_INVALID_FILM` (not a film this library reads) or
/// `EMBER_STATUS_FILM_MISMATCH` (another render's), their messages naming the field.
pub fn decode(bytes: &[u8], this: &FilmIdentity) -> Result<Film> {
    let invalid = |m: String| Error::new(EmberStatus::InvalidFilm, m);
    if bytes.len() >= MAGIC.len() && bytes[..MAGIC.len()] != MAGIC {
        return Err(invalid("magic: the bytes are not an exported ember film (they do not start with EMBRFILM)".into()));
    }
    let mut r = Reader { bytes, at: 0 };
    let truncated = |what: &str| invalid(format!("size: {} bytes end inside the film's header ({what}): the buffer is truncated", bytes.len()));
    r.take(MAGIC.len()).ok_or_else(|| truncated("magic"))?;
    let version = r.u32().ok_or_else(|| truncated("format version"))?;
    if version != FORMAT_VERSION {
        return Err(invalid(format!("format version: the film's is {version}, this library reads {FORMAT_VERSION}")));
    }
    let [width, height, passes] = [r.u32(), r.u32(), r.u32()].map(|v| v.ok_or_else(|| truncated("size and passes")));
    let (width, height, passes) = (width?, height?, passes?);
    let [discarded, splats_outside, saturated, seed] = [r.u64(), r.u64(), r.u64(), r.u64()].map(|v| v.ok_or_else(|| truncated("tallies and seed")));
    let tallies = Tallies { discarded: discarded?, splats_outside: splats_outside?, saturated: saturated? };
    let seed = seed?;
    let max_depth = r.u32().ok_or_else(|| truncated("max depth"))? as i32;
    let tracer = r.u32().ok_or_else(|| truncated("tracer"))?;
    let scene_hash = r.u64().ok_or_else(|| truncated("scene hash"))?;
    let kind = r.u32().ok_or_else(|| truncated("film kind"))?;
    let mut strings = [const { String::new() }; 3];
    for (s, name) in strings.iter_mut().zip(["ember build", "estimator", "configuration"]) {
        let len = r.u16().ok_or_else(|| truncated(name))?;
        let raw = r.take(len as usize).ok_or_else(|| truncated(name))?;
        *s = String::from_utf8_lossy(raw).into_owned();
    }
    // The size the header implies, before the checksum: a truncated buffer says so.
    let pixels = width as u128 * height as u128;
    let weighted = kind == 1;
    let per_pixel = PIXEL_BYTES + if weighted { WEIGHTED_BYTES } else { 0 };
    let expected = r.at as u128 + pixels * per_pixel as u128 + CHECKSUM as u128;
    if bytes.len() as u128 != expected {
        return Err(invalid(format!(
            "size: a {width}x{height} film takes {expected} bytes, the buffer holds {} ({})",
            bytes.len(),
            if (bytes.len() as u128) < expected { "truncated" } else { "bytes past its end" }
        )));
    }
    let body = bytes.len() - CHECKSUM;
    let stored = u64::from_le_bytes(bytes[body..].try_into().expect("8 bytes"));
    if fnv1a(&bytes[..body]) != stored {
        return Err(invalid("checksum: the bytes differ from those exported (damaged)".into()));
    }
    if tracer > 1 {
        return Err(invalid(format!("tracer: {tracer} is neither 0 (built-in BVH) nor 1 (callbacks)")));
    }
    if kind > 1 {
        return Err(invalid(format!("film kind: {kind} is neither 0 (box) nor 1 (weighted)")));
    }
    let [build, estimator, config] = strings;
    let film_identity = FilmIdentity { build, estimator, config, seed, max_depth, callbacks: tracer == 1, scene_hash, width, height, weighted };
    if let Some(problem) = this.mismatch(&film_identity) {
        return Err(Error::new(EmberStatus::FilmMismatch, problem));
    }
    let sums = r
        .take(pixels as usize * PIXEL_BYTES)
        .expect("the size was checked")
        .chunks_exact(PIXEL_BYTES)
        .map(|p| [0, 1, 2].map(|c| u128::from_le_bytes(p[16 * c..16 * c + 16].try_into().expect("16 bytes"))))
        .collect();
    let weights: Vec<WeightedSum> = if weighted {
        r.take(pixels as usize * WEIGHTED_BYTES)
            .expect("the size was checked")
            .chunks_exact(WEIGHTED_BYTES)
            .map(|p| {
                let [r, g, b, weight] = [0, 1, 2, 3].map(|c| u128::from_le_bytes(p[16 * c..16 * c + 16].try_into().expect("16 bytes")));
                WeightedSum { value: [r, g, b], weight }
            })
            .collect()
    } else {
        Vec::new()
    };
    Film::from_exact(width, height, sums, passes, tallies).and_then(|f| f.with_weighted_sums(weights)).map_err(|e| invalid(format!("size: {e}")))
}

/// Writes into an exactly sized buffer.
struct Writer<'a> {
    out: &'a mut [u8],
    at: usize,
}

impl Writer<'_> {
    fn put(&mut self, bytes: &[u8]) {
        self.out[self.at..self.at + bytes.len()].copy_from_slice(bytes);
        self.at += bytes.len();
    }
}

/// Reads from a buffer of unchecked length: `None` past its end.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len())?;
        let out = &self.bytes[self.at..end];
        self.at = end;
        Some(out)
    }
    fn u16(&mut self) -> Option<u16> {
        self.take(2).map(|b| u16::from_le_bytes([b[0], b[1]]))
    }
    fn u32(&mut self) -> Option<u32> {
        self.take(4).map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")))
    }
    fn u64(&mut self) -> Option<u64> {
        self.take(8).map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ember_core::camera::CameraPass;
    use ember_core::pixel_filter::Filter;
    use ember_core::spectrum::Rgb;

    /// A gaussian film's weighted sums survive export and import bit for bit, and a box
    /// film's identity refuses them (issue 52). Injected bug: the weighted sums not
    /// written (the film kind still 1): refused as truncated.
    #[test]
    fn weighted_films_round_trip() {
        let mut film = Film::with_filter(3, 2, Filter::Gaussian { stddev: 0.6 });
        for pass in 0..3 {
            let px: Vec<Rgb> = (0..6).map(|i| Rgb::new(0.25 * (i + pass) as f32, 1.0, 3e8)).collect();
            film.set_camera_samples(CameraPass { seed: 9, pass }, 0..6, &px);
            film.end_pass(1.0);
        }
        let identity = FilmIdentity {
            build: "test".into(),
            estimator: "pt".into(),
            config: "Pt".into(),
            seed: 9,
            max_depth: -1,
            callbacks: false,
            scene_hash: 1,
            width: 3,
            height: 2,
            weighted: true,
        };
        let mut bytes = vec![0; encoded_len(&identity).unwrap()];
        encode(&identity, &film, &mut bytes);
        let back = decode(&bytes, &identity).unwrap();
        assert_eq!(back.weighted_sums(), film.weighted_sums());
        assert_eq!(back.to_rgb_f32(), film.to_rgb_f32());
        let boxed = FilmIdentity { weighted: false, ..identity };
        assert!(decode(&bytes, &boxed).unwrap_err().message.contains("film kind"));
    }
}
