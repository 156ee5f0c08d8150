//! BSDF plugins: `diffuse`, `conductor`, `roughconductor`, `dielectric`,
//! `roughdielectric`, `plastic`, `roughplastic`, `principled`, `twosided`, with Mitsuba
//! 3's parameter names and defaults. Colour parameters (and `principled`'s `roughness`)
//! take a nested or referenced `<texture>` of that name instead of a value (see
//! `textures.rs`).

use ember_core::bsdf::{Material, MicrofacetKind, PrincipledParams, TextureSlot};
use ember_core::geometry::MaterialId;
use ember_core::spectrum::Rgb;

use super::build::Ctx;
use super::props::Props;
use super::xml::Tag;
use super::{Fail, Res};

/// `twosided` chains (through `ref`) deeper than this are rejected.
const MAX_BSDF_DEPTH: u32 = 8;

const BSDF_TYPES: &str = "diffuse, conductor, roughconductor, dielectric, roughdielectric, plastic, roughplastic, principled, twosided";

/// The textures a material's parameters read: (slot, texture id).
type Bindings = Vec<(TextureSlot, u32)>;

/// Named conductors as Mitsuba 3.9.1's `scalar_rgb` variant resolves them
/// (`shared/scenes/README.md`): (name, eta, k).
const CONDUCTORS: [(&str, [f32; 3], [f32; 3]); 4] = [
    ("Al", [1.6575, 0.880405, 0.521244], [9.22381, 6.2695, 4.837]),
    ("Cu", [0.201005, 0.92375, 1.10222], [3.91326, 2.45305, 2.14209]),
    ("Au", [0.143036, 0.375307, 1.44205], [3.983, 2.38556, 1.60336]),
    ("Ag", [0.155276, 0.116728, 0.138388], [4.82835, 3.12222, 2.1469]),
];

/// Mitsuba's named indices of refraction (`include/mitsuba/render/ior.h`).
const IORS: [(&str, f64); 23] = [
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

fn rgb(v: [f32; 3]) -> Rgb {
    Rgb::new(v[0], v[1], v[2])
}

impl Ctx<'_> {
    /// The material id of a `bsdf` object, created on first use and shared by every
    /// shape that refers to the same object.
    pub(crate) fn material(&mut self, idx: usize) -> Res<MaterialId> {
        if let Some(&m) = self.materials.get(&idx) {
            return Ok(m);
        }
        let mut bindings = Bindings::new();
        let m = self.bsdf(idx, 0, &mut bindings)?;
        let id = self.sb.add_material(m);
        for (slot, texture) in bindings {
            self.sb.bind_texture(id, slot, texture);
        }
        self.materials.insert(idx, id);
        Ok(id)
    }

    /// Mitsuba's default for a shape without a BSDF: `diffuse` with reflectance 0.5, or
    /// 0 (black) for a shape that emits (Mitsuba 3's `Shape` constructor: an emitter's
    /// default BSDF reflects nothing). The grey one lit the glossy scene's bulb: light
    /// bounced off the lamp and the image read brighter than Mitsuba's.
    pub(crate) fn default_material(&mut self, emits: bool) -> MaterialId {
        let existing = if emits { self.default_emitter_material } else { self.default_material };
        if let Some(id) = existing {
            return id;
        }
        let id = self.sb.add_material(Material::diffuse(Rgb::splat(if emits { 0.0 } else { 0.5 })));
        if emits {
            self.default_emitter_material = Some(id);
        } else {
            self.default_material = Some(id);
        }
        id
    }

    /// A `<texture>` child named `name`, bound to `slot` in `bindings`, and its mean
    /// value; `None` if there is no such child. Refused if `name` is also a property.
    fn texture_param(&mut self, idx: usize, p: &Props, name: &'static str, slot: TextureSlot, bindings: &mut Bindings) -> Res<Option<Rgb>> {
        let obj = self.obj(idx)?;
        let Some(child) = obj.children.iter().find(|c| c.name.as_deref() == Some(name)) else {
            return Ok(None);
        };
        if p.has(name) {
            return Err(Fail::at(child.loc, format!("`{name}` is given both as a value (line {}) and as a texture", self.line(p.loc_of(name)))));
        }
        let (id, mean) = self.texture(child.obj)?;
        bindings.push((slot, id));
        Ok(Some(mean))
    }

    /// A colour parameter: a `<texture>` child named `name` (its mean is the value, the
    /// binding goes to `bindings`) or the property (default `default`).
    fn color_param(&mut self, idx: usize, p: &mut Props, name: &'static str, default: Rgb, slot: TextureSlot, bindings: &mut Bindings) -> Res<Rgb> {
        match self.texture_param(idx, p, name, slot, bindings)? {
            Some(mean) => Ok(mean),
            None => p.color(name, default),
        }
    }

    /// A float parameter that may be a `<texture>` child named `name` (its mean luminance
    /// is the value, the binding goes to `bindings`), else the property (default `default`).
    fn float_param(&mut self, idx: usize, p: &mut Props, name: &'static str, default: f64, slot: TextureSlot, bindings: &mut Bindings) -> Res<f64> {
        match self.texture_param(idx, p, name, slot, bindings)? {
            Some(mean) => Ok(mean.luminance() as f64),
            None => p.float(name, default),
        }
    }

    /// Mitsuba's `principled`: its parameters and defaults (`PrincipledParams`); `eta` and
    /// `specular` exclude each other, and with a transmission lobe an index-matched η
    /// (η = 1 or specular = 0) is moved off 1 as Mitsuba does. `base_color` and `roughness`
    /// may be textures; the other parameters are floats.
    fn principled(&mut self, idx: usize, p: &mut Props, bindings: &mut Bindings) -> Res<Material> {
        const TEXTURED: [&str; 2] = ["base_color", "roughness"];
        self.check_textures(idx, &TEXTURED)?;
        let d = PrincipledParams::default();
        let base_color = self.color_param(idx, p, "base_color", d.base_color, TextureSlot::Diffuse, bindings)?;
        if !(base_color.is_valid_radiance()) {
            return Err(Fail::at(p.loc_of("base_color"), "`base_color` must be non-negative"));
        }
        let roughness = self.float_param(idx, p, "roughness", d.roughness as f64, TextureSlot::Roughness, bindings)?;
        // Weights in [0, 1] (outside it the model's lobes lose meaning: negative weights,
        // or √(1 − 0.9 anisotropic) of a negative number).
        let mut unit = |name: &'static str, default: f32| -> Res<f32> {
            let v = p.float(name, default as f64)?;
            if !(0.0..=1.0).contains(&v) {
                return Err(Fail::at(p.loc_of(name), format!("`{name}` must lie in [0, 1], got {v}")));
            }
            Ok(v as f32)
        };
        let (anisotropic, metallic, spec_tint) = (unit("anisotropic", d.anisotropic)?, unit("metallic", d.metallic)?, unit("spec_tint", d.spec_tint)?);
        let (sheen_tint, flatness, clearcoat_gloss) =
            (unit("sheen_tint", d.sheen_tint)?, unit("flatness", d.flatness)?, unit("clearcoat_gloss", d.clearcoat_gloss)?);
        let spec_trans = unit("spec_trans", d.spec_trans)?;
        let mut non_negative = |name: &'static str, default: f64| -> Res<f32> {
            let v = p.float(name, default)?;
            if !(v >= 0.0 && v.is_finite()) {
                return Err(Fail::at(p.loc_of(name), format!("`{name}` must be finite and non-negative, got {v}")));
            }
            Ok(v as f32)
        };
        let (sheen, clearcoat) = (non_negative("sheen", d.sheen as f64)?, non_negative("clearcoat", d.clearcoat as f64)?);
        let diffuse_sampling_rate = non_negative("diffuse_reflectance_sampling_rate", 1.0)?;
        let specular_sampling_rate = non_negative("main_specular_sampling_rate", 1.0)?;
        let clearcoat_sampling_rate = non_negative("clearcoat_sampling_rate", 1.0)?;
        if !(roughness >= 0.0 && roughness.is_finite()) {
            return Err(Fail::at(p.loc_of("roughness"), format!("`roughness` must be finite and non-negative, got {roughness}")));
        }
        let transmits = spec_trans > 0.0;
        let eta = match (p.has("eta"), p.has("specular")) {
            (true, true) => return Err(Fail::at(p.loc_of("specular"), "give either `eta` or `specular`, not both (as Mitsuba)")),
            (true, false) => {
                let eta = p.float("eta", 1.5)?;
                if !(eta > 0.0 && eta.is_finite()) {
                    return Err(Fail::at(p.loc_of("eta"), format!("`eta` must be positive, got {eta}")));
                }
                if transmits && eta == 1.0 { 1.001 } else { eta as f32 }
            }
            _ => {
                let specular = p.float("specular", 0.5)?;
                // specular = 12.5 would put R0 at 1 (η = ∞).
                if !((0.0..12.5).contains(&specular)) {
                    return Err(Fail::at(p.loc_of("specular"), format!("`specular` must lie in [0, 12.5), got {specular}")));
                }
                let specular = if transmits && specular == 0.0 { 1e-3 } else { specular as f32 };
                PrincipledParams::eta_from_specular(specular)
            }
        };
        Ok(Material::principled(PrincipledParams {
            base_color,
            roughness: roughness as f32,
            anisotropic,
            metallic,
            spec_tint,
            sheen,
            sheen_tint,
            flatness,
            clearcoat,
            clearcoat_gloss,
            spec_trans,
            eta,
            diffuse_sampling_rate,
            specular_sampling_rate,
            clearcoat_sampling_rate,
        }))
    }

    /// Textures nested in BSDF `idx` must be named for parameters it reads (`names`).
    fn check_textures(&self, idx: usize, names: &[&str]) -> Res<()> {
        let obj = self.obj(idx)?;
        self.check_children(obj, &[Tag::Texture])?;
        for c in &obj.children {
            match c.name.as_deref() {
                Some(n) if names.contains(&n) => {}
                Some(n) => return Err(Fail::at(c.loc, format!("{} has no textured parameter `{n}` (it takes: {})", obj.label(), names.join(", ")))),
                None => return Err(Fail::at(c.loc, format!("a <texture> in {} needs a `name`: the parameter it sets ({})", obj.label(), names.join(", ")))),
            }
        }
        Ok(())
    }

    fn bsdf(&mut self, idx: usize, depth: u32, bindings: &mut Bindings) -> Res<Material> {
        let obj = self.obj(idx)?;
        self.mark(idx);
        if depth > MAX_BSDF_DEPTH {
            return Err(Fail::at(obj.loc, format!("`twosided` BSDFs nested more than {MAX_BSDF_DEPTH} deep")));
        }
        let mut p = Props::new(obj);
        let m = match obj.kind.as_str() {
            "diffuse" => {
                self.check_textures(idx, &["reflectance"])?;
                Material::diffuse(self.color_param(idx, &mut p, "reflectance", Rgb::splat(0.5), TextureSlot::Diffuse, bindings)?)
            }
            "conductor" | "roughconductor" => {
                self.check_textures(idx, &["specular_reflectance"])?;
                let (eta, k) = conductor_ior(&mut p)?;
                let spec = self.color_param(idx, &mut p, "specular_reflectance", Rgb::ONE, TextureSlot::SpecularReflectance, bindings)?;
                if obj.kind == "conductor" {
                    Material::conductor(eta, k, spec)
                } else {
                    let (kind, alpha) = microfacet(&mut p)?;
                    Material::rough_conductor(kind, alpha, eta, k, spec)
                }
            }
            "dielectric" | "roughdielectric" => {
                self.check_textures(idx, &["specular_reflectance", "specular_transmittance"])?;
                let int_ior = ior(&mut p, "int_ior", 1.5046)?;
                let ext_ior = ior(&mut p, "ext_ior", 1.000277)?;
                let refl = self.color_param(idx, &mut p, "specular_reflectance", Rgb::ONE, TextureSlot::SpecularReflectance, bindings)?;
                let trans = self.color_param(idx, &mut p, "specular_transmittance", Rgb::ONE, TextureSlot::SpecularTransmittance, bindings)?;
                if obj.kind == "dielectric" {
                    Material::dielectric(int_ior, ext_ior, refl, trans)
                } else {
                    let (kind, alpha) = microfacet(&mut p)?;
                    Material::rough_dielectric(kind, alpha, int_ior, ext_ior, refl, trans)
                }
            }
            "plastic" | "roughplastic" => {
                self.check_textures(idx, &["diffuse_reflectance", "specular_reflectance"])?;
                // Mitsuba's defaults: polypropylene in air, ρ = 0.5, Beckmann α = 0.1.
                let int_ior = ior(&mut p, "int_ior", 1.49)?;
                let ext_ior = ior(&mut p, "ext_ior", 1.000277)?;
                if int_ior == ext_ior {
                    return Err(Fail::at(p.loc_of("int_ior"), "`int_ior` and `ext_ior` must differ (a coating without an interface)"));
                }
                let diffuse = self.color_param(idx, &mut p, "diffuse_reflectance", Rgb::splat(0.5), TextureSlot::Diffuse, bindings)?;
                let specular = self.color_param(idx, &mut p, "specular_reflectance", Rgb::ONE, TextureSlot::SpecularReflectance, bindings)?;
                for (name, c) in [("diffuse_reflectance", diffuse), ("specular_reflectance", specular)] {
                    if !c.is_valid_radiance() {
                        return Err(Fail::at(p.loc_of(name), format!("`{name}` must be non-negative")));
                    }
                }
                let nonlinear = p.bool("nonlinear", false)?;
                if obj.kind == "plastic" {
                    p.finish()?;
                    return Ok(Material::plastic(int_ior, ext_ior, diffuse, specular, nonlinear));
                }
                let (kind, alpha) = microfacet(&mut p)?;
                // One coating table per distinct (distribution, α, indices): they cost up to
                // a second each to build (Beckmann).
                let key = (kind == MicrofacetKind::Ggx, alpha.to_bits(), int_ior.to_bits(), ext_ior.to_bits());
                let coating = *self.plastic_coatings.entry(key).or_insert_with(|| Material::plastic_coating(kind, alpha, int_ior, ext_ior));
                Material::rough_plastic_coated(&coating, diffuse, specular, nonlinear)
            }
            "principled" => self.principled(idx, &mut p, bindings)?,
            "twosided" => {
                self.check_children(obj, &[Tag::Bsdf])?;
                let inner = match obj.children[..] {
                    [ref c] => c.obj,
                    [] => return Err(Fail::at(obj.loc, "`twosided` needs one nested <bsdf> (or <ref>)")),
                    [_, ref second, ..] => {
                        return Err(Fail::at(second.loc, "`twosided` with different front and back BSDFs is not supported: give one nested <bsdf>"));
                    }
                };
                let m = self.bsdf(inner, depth + 1, bindings)?;
                if m.has_transmission() {
                    return Err(Fail::at(obj.loc, "`twosided` cannot wrap a BSDF that transmits (dielectric): it is two-sided already"));
                }
                m.two_sided()
            }
            other => {
                return Err(Fail::at(obj.loc, format!("unsupported bsdf type \"{other}\" (supported: {BSDF_TYPES})")));
            }
        };
        p.finish()?;
        Ok(m)
    }
}

/// `material` (a name from [`CONDUCTORS`], or "none" = perfect mirror) or `eta` / `k`.
fn conductor_ior(p: &mut Props) -> Res<(Rgb, Rgb)> {
    let has_eta_k = p.has("eta") || p.has("k");
    match p.string_opt("material")? {
        Some(name) => {
            if has_eta_k {
                let loc = p.loc_of("material");
                return Err(Fail::at(loc, "give either `material` or `eta`/`k`, not both (as Mitsuba)"));
            }
            if name == "none" {
                return Ok((Rgb::ZERO, Rgb::ONE));
            }
            match CONDUCTORS.iter().find(|(n, _, _)| *n == name) {
                Some((_, eta, k)) => Ok((rgb(*eta), rgb(*k))),
                None => {
                    let names: Vec<&str> = CONDUCTORS.iter().map(|c| c.0).collect();
                    Err(Fail::at(
                        p.loc_of("material"),
                        format!("unknown conductor material \"{name}\" (supported: {}, none; or give `eta` and `k`)", names.join(", ")),
                    ))
                }
            }
        }
        // Mitsuba's default material is "none": η = 0, k = 1, a perfect mirror.
        None => Ok((p.color("eta", Rgb::ZERO)?, p.color("k", Rgb::ONE)?)),
    }
}

/// `distribution` (beckmann, Mitsuba's default, or ggx) and `alpha` (default 0.1).
fn microfacet(p: &mut Props) -> Res<(MicrofacetKind, f32)> {
    let kind = match p.string_opt("distribution")?.map(str::to_ascii_lowercase).as_deref() {
        None | Some("beckmann") => MicrofacetKind::Beckmann,
        Some("ggx") => MicrofacetKind::Ggx,
        Some(other) => {
            return Err(Fail::at(p.loc_of("distribution"), format!("unknown distribution \"{other}\" (supported: beckmann, ggx)")));
        }
    };
    let alpha = p.float("alpha", 0.1)?;
    if !(alpha >= 0.0) {
        return Err(Fail::at(p.loc_of("alpha"), format!("`alpha` must be non-negative, got {alpha}")));
    }
    Ok((kind, alpha as f32))
}

/// An index of refraction: a `float` or one of Mitsuba's names ([`IORS`]).
fn ior(p: &mut Props, name: &'static str, default: f64) -> Res<f32> {
    let v = if p.value_tag(name) == Some("string") {
        let s = p.string_opt(name)?.unwrap_or_default();
        let key = s.to_ascii_lowercase();
        match IORS.iter().find(|(n, _)| *n == key) {
            Some(&(_, v)) => v,
            None => {
                let names: Vec<&str> = IORS.iter().map(|i| i.0).collect();
                return Err(Fail::at(p.loc_of(name), format!("unknown index of refraction \"{s}\" (a number or one of: {})", names.join(", "))));
            }
        }
    } else {
        p.float(name, default)?
    };
    if !(v > 0.0) {
        return Err(Fail::at(p.loc_of(name), format!("`{name}` must be positive, got {v}")));
    }
    Ok(v as f32)
}
