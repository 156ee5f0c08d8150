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
