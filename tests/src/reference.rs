//! The benchmark suite's Mitsuba 3 references, read from `../shared/scenes` beside the
//! repository.

use std::path::PathBuf;

/// Folder of the suite's scenes (`<repo>/../shared/scenes`).
pub fn scenes_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes")
}

/// A linear RGB image.
#[derive(Clone, Debug)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
}

impl Image {
    /// Mean of each channel over the `bw × bh` block of blocks (bx, by).
    pub fn block_mean(&self, bx: usize, by: usize, bw: usize, bh: usize) -> [f64; 3] {
        let mut s = [0.0f64; 3];
        for y in by * bh..(by + 1) * bh {
            for x in bx * bw..(bx + 1) * bw {
                let p = self.pixels[y * self.width + x];
                for c in 0..3 {
                    s[c] += p[c] as f64;
                }
            }
        }
        s.map(|v| v / (bw * bh) as f64)
    }
}

/// Read the first RGB(A) layer of an EXR file.
pub fn read_exr(path: &std::path::Path) -> Result<Image, String> {
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |resolution, _| Image { width: resolution.width(), height: resolution.height(), pixels: vec![[0.0; 3]; resolution.width() * resolution.height()] },
        |img: &mut Image, pos: exr::math::Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
            let w = img.width;
            img.pixels[pos.y() * w + pos.x()] = [r, g, b];
        },
    )
    .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(image.layer_data.channel_data.pixels)
}

/// A Mitsuba reference with its two half-sample images, for per-block z-tests of our
/// renders against it (the environment-map and `textured` checks).
#[derive(Clone, Debug)]
pub struct Reference {
    pub image: Image,
    pub half_a: Image,
    pub half_b: Image,
    /// The reference's samples per pixel (both halves together).
    pub spp: f64,
}

/// The worst block of a comparison: |z|, block (x, y), channel, ours / reference.
#[derive(Clone, Copy, Debug, Default)]
pub struct Worst {
    pub z: f64,
    pub block: (usize, usize),
    pub channel: usize,
    pub ratio: f64,
}

impl Reference {
    /// `reference.exr`, `reference-half-a.exr` and `reference-half-b.exr` of `dir`.
    pub fn load(dir: &std::path::Path, spp: f64) -> Result<Self, String> {
        Ok(Self {
            image: read_exr(&dir.join("reference.exr"))?,
            half_a: read_exr(&dir.join("reference-half-a.exr"))?,
            half_b: read_exr(&dir.join("reference-half-b.exr"))?,
            spp,
        })
    }

    /// z-test, per `block`-pixel square and channel, of `stats` (per-block statistics of
    /// independent films of `our_spp` samples per pixel each; [`push_film_blocks`]) against
    /// the reference, Šidák-corrected at family level 0.01; panics naming the first block
    /// that fails. The reference's standard error is half its halves' difference, but at
    /// least ours scaled by the sample counts (two halves estimate it poorly; Mitsuba's
    /// path tracer is no less noisy per sample than ours), and `floor_rel` of the value
    /// (for nearly noise-free blocks).
    pub fn assert_blocks_match(&self, stats: &[[crate::stats::MeanVar; 3]], block: usize, our_spp: f64, floor_rel: f64) -> Worst {
        let (nbx, nby) = (self.image.width / block, self.image.height / block);
        assert_eq!(stats.len(), nbx * nby, "one statistic per block");
        let alpha = crate::chi2::sidak(0.01, nbx * nby * 3);
        let mut worst = Worst::default();
        for by in 0..nby {
            for bx in 0..nbx {
                let r = self.image.block_mean(bx, by, block, block);
                let (a, b) = (self.half_a.block_mean(bx, by, block, block), self.half_b.block_mean(bx, by, block, block));
                for c in 0..3 {
                    let ours = &stats[by * nbx + bx][c];
                    let ref_se = (0.5 * (a[c] - b[c]).abs()).max(ours.std_error() * (our_spp / self.spp).sqrt());
                    let se = (ours.std_error().powi(2) + ref_se * ref_se + (floor_rel * r[c]).powi(2)).sqrt();
                    let z = (ours.mean() - r[c]) / se;
                    if z.abs() > worst.z {
                        worst = Worst { z: z.abs(), block: (bx, by), channel: c, ratio: ours.mean() / r[c] };
                    }
                    assert!(
                        crate::stats::normal_two_sided_p(z) > alpha,
                        "block ({bx}, {by}) channel {c}: ours {} ± {}, Mitsuba {} ± {ref_se} (z = {z:.2})",
                        ours.mean(),
                        ours.std_error(),
                        r[c]
                    );
                }
            }
        }
        worst
    }
}

/// Add one film's block means (`sums` of `width`-wide pixels over `passes` passes, in
/// `block`-pixel squares, row-major) to per-block statistics.
pub fn push_film_blocks(stats: &mut [[crate::stats::MeanVar; 3]], sums: &[[f64; 3]], width: usize, passes: u32, block: usize) {
    let height = sums.len() / width;
    let nbx = width / block;
    for by in 0..height / block {
        for bx in 0..nbx {
            let mut m = [0.0f64; 3];
            for y in by * block..(by + 1) * block {
                for x in bx * block..(bx + 1) * block {
                    for c in 0..3 {
                        m[c] += sums[y * width + x][c] / passes as f64 / (block * block) as f64;
                    }
                }
            }
            for c in 0..3 {
                stats[by * nbx + bx][c].push(m[c]);
            }
        }
    }
}
