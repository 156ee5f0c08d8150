//! Texture plugins: `bitmap` (PNG or OpenEXR) and `checkerboard`, with Mitsuba 3's
//! parameter names and defaults. The files are decoded by [`super::images`]; the core gets
//! linear texels ([`ember_core::texture`] has the lookup conventions).

use ember_core::spectrum::Rgb;
use ember_core::texture::{Bitmap, Texture, UvTransform, WrapMode};
use glam::DMat4;

use super::build::Ctx;
use super::images::read_image;
use super::props::Props;
use super::{Fail, Res};

impl Ctx<'_> {
    /// The texture of object `idx`: its id in the scene and its mean colour, built once
    /// and shared by every material that refers to it.
    pub(crate) fn texture(&mut self, idx: usize) -> Res<(u32, Rgb)> {
        if let Some(&t) = self.textures.get(&idx) {
            return Ok(t);
        }
        let obj = self.obj(idx)?;
        self.mark(idx);
        self.no_children(obj)?;
        let mut p = Props::new(obj);
        let texture = match obj.kind.as_str() {
            "checkerboard" => {
                let color0 = p.color("color0", Rgb::splat(0.4))?;
                let color1 = p.color("color1", Rgb::splat(0.2))?;
                for (name, c) in [("color0", color0), ("color1", color1)] {
                    if !c.is_valid_radiance() {
                        return Err(Fail::at(p.loc_of(name), format!("`{name}` must be non-negative and finite")));
                    }
                }
                Texture::Checkerboard { color0, color1, to_uv: to_uv(&mut p)? }
            }
            "bitmap" => {
                let file_loc = p.loc_of("filename");
                let filename = p.string_opt("filename")?.ok_or_else(|| Fail::at(obj.loc, "the bitmap needs a `filename` (PNG or OpenEXR)"))?;
                let bilinear = match p.string_opt("filter_type")? {
                    None | Some("bilinear") => true,
                    Some("nearest") => false,
                    Some(other) => return Err(Fail::at(p.loc_of("filter_type"), format!("unknown filter_type \"{other}\" (supported: bilinear, nearest)"))),
                };
                let wrap = match p.string_opt("wrap_mode")? {
                    None | Some("repeat") => WrapMode::Repeat,
                    Some("mirror") => WrapMode::Mirror,
                    Some("clamp") => WrapMode::Clamp,
                    Some(other) => return Err(Fail::at(p.loc_of("wrap_mode"), format!("unknown wrap_mode \"{other}\" (supported: repeat, mirror, clamp)"))),
                };
                let raw = p.bool("raw", false)?;
                let to_uv = to_uv(&mut p)?;
                let path = self.base_dir.join(filename);
                self.inputs.push(path.clone());
                let (w, h, texels) = read_image(&path, raw).map_err(|e| Fail::at(file_loc, format!("bitmap \"{}\": {e}", path.display())))?;
                let bitmap = Bitmap::new(w, h, texels, wrap, bilinear).map_err(|e| Fail::at(file_loc, format!("bitmap \"{}\": {e}", path.display())))?;
                Texture::Bitmap { bitmap, to_uv }
            }
            other => return Err(Fail::at(obj.loc, format!("unsupported texture type \"{other}\" (supported: bitmap, checkerboard)"))),
        };
        p.finish()?;
        let mean = texture.mean();
        let id = self.sb.add_texture(texture);
        self.textures.insert(idx, (id, mean));
        Ok((id, mean))
    }
}

/// Mitsuba's `to_uv` (an affine map of the uv plane): the 4 × 4 transform's upper-left
/// 2 × 2 block and the x, y of its translation.
fn to_uv(p: &mut Props) -> Res<UvTransform> {
    let loc = p.loc_of("to_uv");
    let m: DMat4 = p.transform("to_uv")?;
    let t =
        UvTransform { x: m.x_axis.truncate().truncate().as_vec2(), y: m.y_axis.truncate().truncate().as_vec2(), t: m.w_axis.truncate().truncate().as_vec2() };
    if ![t.x, t.y, t.t].iter().all(|v| v.is_finite()) {
        return Err(Fail::at(loc, "`to_uv` is not finite"));
    }
    Ok(t)
}
