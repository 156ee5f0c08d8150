//! Second pass: instantiate the parsed objects into a [`SceneBuilder`]: the scene's
//! members in document order, then the camera; emitters, sensor, film, sampler and
//! integrator plugins live here, BSDFs in [`super::materials`], shapes in
//! [`super::shapes`].

use std::collections::HashMap;
use std::path::Path;

use glam::{DMat4, DVec3};

use ember_core::bsdf::PlasticCoating;
use ember_core::camera::{FovAxis, Lens, PerspectiveCamera};
use ember_core::geometry::MaterialId;
use ember_core::light::{EnvMapError, Light};
use ember_core::pixel_filter::Filter;
use ember_core::scene::{AreaEmission, SceneBuilder};
use ember_core::spectrum::Rgb;

use super::positions::Positions;
use super::props::Props;
use super::transform;
use super::xml::{Obj, Parsed, Tag};
use super::{Fail, LoadOptions, LoadedScene, Loc, Progress, Res};

/// Largest film side accepted (a guard against absurd allocations downstream).
const MAX_FILM_SIDE: i64 = 1 << 16;

/// Mitsuba's `hdrfilm` default size.
const DEFAULT_FILM: (u32, u32) = (768, 576);

/// Where each top-level shape's and emitter's geometry and lights end in the builder:
/// (triangles, spheres, lights) after it, and its place in the file (read by module
/// `media`, which holds its methods, to name what sits inside a medium).
#[derive(Debug, Default)]
pub(crate) struct Placed {
    pub(super) ends: Vec<(usize, usize, usize, Loc)>,
}

/// Instantiation state.
#[derive(Debug)]
pub(crate) struct Ctx<'a> {
    pub parsed: &'a Parsed,
    /// Resolves places into lines for messages.
    pub positions: &'a Positions<'a>,
    /// Every file the scene reads besides itself (meshes, textures, environment maps):
    /// outputs must not overwrite them.
    pub inputs: Vec<std::path::PathBuf>,
    pub sb: SceneBuilder,
    pub warnings: Vec<String>,
    pub base_dir: &'a Path,
    /// Material of each `bsdf` object already added.
    pub materials: HashMap<usize, MaterialId>,
    pub default_material: Option<MaterialId>,
    /// The same for shapes that emit (black).
    pub default_emitter_material: Option<MaterialId>,
    /// Objects that were instantiated (to warn about unused declarations).
    pub used: Vec<bool>,
    /// World → render frame: the translation by minus the camera position, composed in
    /// f64 with every `to_world` before anything is rounded to f32 (see
    /// [`camera_centred_frame`]).
    pub render_frame: DMat4,
    /// Rough plastic coatings built so far, by (GGX?, α, int_ior, ext_ior) bits.
    pub plastic_coatings: HashMap<(bool, u32, u32, u32), PlasticCoating>,
    /// Textures built so far, by object: their id in the scene and their mean colour.
    pub textures: HashMap<usize, (u32, Rgb)>,
}

/// The camera-centred render frame (pbrt-v4's "camera-world" space): a translation by
/// minus the sensor's position, so that f32 positions keep their precision near the
/// camera however far the scene sits from the world origin. A scene translated by 1e5
/// would otherwise lose everything below f32's ulp there (~0.008), e.g. the Cornell box's
/// light gap. Lights and geometry are translation-invariant, so the image is unchanged.
/// Identity when the file has no sensor (the error is reported later).
fn camera_centred_frame(parsed: &Parsed) -> DMat4 {
    let sensor = parsed.top.iter().filter_map(|&i| parsed.objs.get(i)).find(|o| o.tag == Tag::Sensor);
    let origin = sensor.and_then(|o| Props::new(o).transform_opt("to_world").ok().flatten()).map(|m| m.transform_point3(DVec3::ZERO));
    match origin {
        Some(o) if o.is_finite() => DMat4::from_translation(-o),
        _ => DMat4::IDENTITY,
    }
}

/// What the sensor gives besides the camera transform.
struct SensorSpec {
    to_world: DMat4,
    fov: f32,
    fov_axis: FovAxis,
    width: u32,
    height: u32,
    spp: Option<u32>,
    lens: Option<Lens>,
    filter: Filter,
}

pub(crate) fn instantiate(parsed: Parsed, positions: &Positions, base_dir: &Path, options: &LoadOptions, progress: &mut Progress) -> Res<LoadedScene> {
    let mut ctx = Ctx {
        parsed: &parsed,
        positions,
        sb: SceneBuilder::new(),
        inputs: Vec::new(),
        warnings: parsed.warnings.clone(),
        base_dir,
        materials: HashMap::new(),
        default_material: None,
        default_emitter_material: None,
        used: vec![false; parsed.objs.len()],
        render_frame: camera_centred_frame(&parsed),
        plastic_coatings: HashMap::new(),
        textures: HashMap::new(),
    };
    let mut sensor: Option<(SensorSpec, Loc)> = None;
    let mut integrator: Option<(Option<i32>, Loc)> = None;
    let mut shapes = 0;
    // Where each shape's and emitter's geometry and lights end, for the media check.
    let mut placed = Placed::default();
    for &idx in &parsed.top {
        let obj = ctx.obj(idx)?;
        if !matches!(obj.tag, Tag::Bsdf | Tag::Film | Tag::RFilter | Tag::Sampler | Tag::Texture | Tag::Medium) {
            ctx.mark(idx);
        }
        match obj.tag {
            Tag::Shape => {
                ctx.shape(idx)?;
                placed.record(&ctx.sb, obj.loc);
                shapes += 1;
                progress.shape_done(shapes);
            }
            Tag::Emitter => {
                ctx.emitter(idx)?;
                placed.record(&ctx.sb, obj.loc);
            }
            Tag::Sensor => {
                if let Some((_, first)) = &sensor {
                    return Err(Fail::at(obj.loc, format!("only one <sensor> is supported (the first is at line {})", ctx.line(*first))));
                }
                sensor = Some((ctx.sensor(idx)?, obj.loc));
            }
            Tag::Integrator => {
                if let Some((_, first)) = &integrator {
                    return Err(Fail::at(obj.loc, format!("only one <integrator> is supported (the first is at line {})", ctx.line(*first))));
                }
                integrator = Some((ctx.integrator(idx)?, obj.loc));
            }
            // Declarations, instantiated where a `ref` uses them.
            Tag::Bsdf | Tag::Film | Tag::RFilter | Tag::Sampler | Tag::Texture | Tag::Medium => {}
        }
    }
    for &idx in &parsed.top {
        let obj = ctx.obj(idx)?;
        if !ctx.used[idx] {
            let id = obj.id.as_deref().map(|i| format!(" id=\"{i}\"")).unwrap_or_default();
            ctx.warnings.push(format!("line {}: {}{id} is declared but never used", ctx.line(obj.loc), obj.label()));
        }
    }
    let (spec, sensor_loc) = sensor.ok_or_else(|| Fail::nowhere("the scene has no <sensor> (a perspective camera is required)"))?;
    override_side(options.width, "width")?;
    override_side(options.height, "height")?;
    let (width, height) = super::film_size((spec.width, spec.height), options.width, options.height);
    if width as i64 > MAX_FILM_SIDE || height as i64 > MAX_FILM_SIDE {
        return Err(Fail::nowhere(format!(
            "the film would be {width}x{height} (the file's {}x{} scaled to keep its aspect ratio), more than {MAX_FILM_SIDE} pixels a side; give both the width and the height",
            spec.width, spec.height
        )));
    }
    let camera = PerspectiveCamera::new(spec.to_world.as_mat4(), spec.fov, spec.fov_axis, width, height).with_lens(spec.lens).with_filter(spec.filter);
    ctx.sb.set_camera(camera);
    if let Some((medium, what)) = ctx.sb.medium_intrusion() {
        return Err(placed.refuse_intrusion(&ctx, medium, what, Some(sensor_loc)));
    }
    let world_origin = -ctx.render_frame.w_axis.truncate();
    progress.finish();
    Ok(LoadedScene {
        builder: ctx.sb,
        max_depth: integrator.and_then(|(d, _)| d),
        spp: spec.spp,
        width,
        height,
        warnings: ctx.warnings,
        world_origin,
        inputs: ctx.inputs,
    })
}

fn override_side(option: Option<u32>, what: &str) -> Res<()> {
    match option {
        Some(0) => Err(Fail::nowhere(format!("the {what} override must be positive"))),
        Some(v) if v as i64 > MAX_FILM_SIDE => Err(Fail::nowhere(format!("the {what} override {v} exceeds {MAX_FILM_SIDE}"))),
        _ => Ok(()),
    }
}

impl<'a> Ctx<'a> {
    /// The line of `loc`, for a message.
    pub(crate) fn line(&self, loc: Loc) -> u32 {
        self.positions.line(loc)
    }

    /// An object by index.
    pub(crate) fn obj(&self, idx: usize) -> Res<&'a Obj> {
        let parsed = self.parsed;
        parsed.objs.get(idx).ok_or_else(|| Fail::nowhere("internal error: bad object index"))
    }

    /// Reject nested objects whose category is not in `allowed`.
    pub(crate) fn check_children(&self, obj: &Obj, allowed: &[Tag]) -> Res<()> {
        for c in &obj.children {
            let t = self.obj(c.obj)?;
            if !allowed.contains(&t.tag) {
                if t.tag == Tag::Medium && matches!(obj.tag, Tag::Sensor | Tag::Emitter) {
                    return Err(Fail::at(
                        c.loc,
                        format!(
                            "{} cannot sit in a medium: ember's camera and lights are in vacuum (only a shape's absorbing `interior` is modelled, with nothing inside it)",
                            obj.label()
                        ),
                    ));
                }
                let what = if allowed.is_empty() {
                    "no nested objects".to_string()
                } else {
                    allowed.iter().map(|t| format!("<{}>", t.name())).collect::<Vec<_>>().join(", ")
                };
                return Err(Fail::at(c.loc, format!("{} cannot contain {} (it accepts {what})", obj.label(), t.label())));
            }
        }
        Ok(())
    }

    pub(crate) fn no_children(&self, obj: &Obj) -> Res<()> {
        self.check_children(obj, &[])
    }

    /// The nested object of category `tag`, at most one.
    pub(crate) fn single_child(&self, obj: &Obj, tag: Tag) -> Res<Option<usize>> {
        let mut found = None;
        for c in &obj.children {
            if self.obj(c.obj)?.tag == tag {
                if found.is_some() {
                    return Err(Fail::at(c.loc, format!("{} takes at most one <{}>", obj.label(), tag.name())));
                }
                found = Some(c.obj);
            }
        }
        Ok(found)
    }

    /// Mark a declaration as used by a reference (or nesting).
    pub(crate) fn mark(&mut self, idx: usize) {
        if let Some(u) = self.used.get_mut(idx) {
            *u = true;
        }
    }

    /// An `area` emitter nested in a shape.
    pub(crate) fn area_emission(&mut self, idx: usize) -> Res<AreaEmission> {
        let obj = self.obj(idx)?;
        self.mark(idx);
        if obj.kind != "area" {
            return Err(Fail::at(obj.loc, format!("only `area` emitters can be nested in a <shape>; a \"{}\" emitter belongs directly in <scene>", obj.kind)));
        }
        self.no_children(obj)?;
        let mut p = Props::new(obj);
        let radiance = p.color("radiance", Rgb::ONE)?;
        let radiance = nonnegative(&p, "radiance", radiance)?;
        p.finish()?;
        Ok(AreaEmission { radiance, two_sided: false })
    }

    /// A top-level emitter: `point`, `spot`, `directional` or `constant`.
    fn emitter(&mut self, idx: usize) -> Res<()> {
        let obj = self.obj(idx)?;
        self.no_children(obj)?;
        let mut p = Props::new(obj);
        let light = match obj.kind.as_str() {
            "point" => {
                let position = match (p.point_opt("position")?, p.transform_opt("to_world")?) {
                    (Some(_), Some(_)) => return Err(Fail::at(p.loc_of("to_world"), "give either `position` or `to_world`, not both")),
                    (Some(v), None) => DVec3::from_array(v),
                    (None, Some(m)) => m.transform_point3(DVec3::ZERO),
                    (None, None) => DVec3::ZERO,
                };
                let intensity = p.color("intensity", Rgb::ONE)?;
                let intensity = nonnegative(&p, "intensity", intensity)?;
                Light::point(self.render_frame.transform_point3(position).as_vec3(), intensity)
            }
            "spot" => {
                let m = self.render_frame * p.transform("to_world")?;
                let direction = m.transform_vector3(DVec3::Z);
                if !(direction.length() > 0.0) {
                    return Err(Fail::at(p.loc_of("to_world"), "the spot light's `to_world` is singular"));
                }
                let intensity = p.color("intensity", Rgb::ONE)?;
                let cutoff = p.float("cutoff_angle", 20.0)?;
                if !(cutoff > 0.0 && cutoff <= 180.0) {
                    return Err(Fail::at(p.loc_of("cutoff_angle"), format!("`cutoff_angle` must be in (0, 180] degrees, got {cutoff}")));
                }
                let mut beam = p.float("beam_width", 0.75 * cutoff)?;
                if !(beam >= 0.0) {
                    return Err(Fail::at(p.loc_of("beam_width"), format!("`beam_width` must be non-negative, got {beam}")));
                }
                if beam > cutoff {
                    self.warnings.push(format!("line {}: spot `beam_width` {beam} exceeds `cutoff_angle` {cutoff}; clamped", self.line(obj.loc)));
                    beam = cutoff;
                }
                let intensity = nonnegative(&p, "intensity", intensity)?;
                let position = m.transform_point3(DVec3::ZERO);
                Light::spot(position.as_vec3(), direction.normalize().as_vec3(), intensity, cutoff as f32, beam as f32)
            }
            "directional" => {
                let direction = match (p.vector_opt("direction")?, p.transform_opt("to_world")?) {
                    (Some(_), Some(_)) => return Err(Fail::at(p.loc_of("to_world"), "give either `direction` or `to_world`, not both")),
                    (Some(v), None) => DVec3::from_array(v),
                    (None, Some(m)) => m.transform_vector3(DVec3::Z),
                    (None, None) => DVec3::Z,
                };
                if !(direction.length() > 0.0) {
                    return Err(Fail::at(obj.loc, "the directional light's direction is zero"));
                }
                let irradiance = p.color("irradiance", Rgb::ONE)?;
                let irradiance = nonnegative(&p, "irradiance", irradiance)?;
                Light::directional(direction.normalize().as_vec3(), irradiance)
            }
            "constant" => {
                let radiance = p.color("radiance", Rgb::ONE)?;
                let radiance = nonnegative(&p, "radiance", radiance)?;
                Light::constant_environment(radiance)
            }
            "envmap" => self.envmap(obj, &mut p)?,
            "area" => return Err(Fail::at(obj.loc, "an `area` emitter must be nested in the <shape> that emits")),
            other => {
                return Err(Fail::at(
                    obj.loc,
                    format!("unsupported emitter type \"{other}\" (supported: area inside a shape; point, spot, directional, constant, envmap)"),
                ));
            }
        };
        p.finish()?;
        self.sb.add_light(light);
        Ok(())
    }

    /// Mitsuba's `envmap`: a latitude–longitude image (EXR, RGBE or PFM linear; PNG or JPEG
    /// through the sRGB curve) at `filename`, relative
    /// to the scene file, times `scale`, in the frame of `to_world` (a rotation).
    fn envmap(&mut self, obj: &Obj, p: &mut Props) -> Res<Light> {
        let file_loc = p.loc_of("filename");
        let filename = p.string_opt("filename")?.ok_or_else(|| Fail::at(obj.loc, "the envmap needs a `filename` (a latitude-longitude image)"))?;
        let scale = p.float("scale", 1.0)?;
        if !(scale >= 0.0 && scale.is_finite()) {
            return Err(Fail::at(p.loc_of("scale"), format!("`scale` must be non-negative and finite, got {scale}")));
        }
        let m = self.render_frame * p.transform("to_world")?;
        let axes = [m.x_axis.truncate().as_vec3(), m.y_axis.truncate().as_vec3(), m.z_axis.truncate().as_vec3()];
        let path = self.base_dir.join(filename);
        self.inputs.push(path.clone());
        // Any image a bitmap reads: float formats as stored, 8-bit ones through the sRGB curve.
        let (width, height, texels) = super::images::read_image(&path, false).map_err(|e| Fail::at(file_loc, format!("envmap \"{}\": {e}", path.display())))?;
        Light::environment_map(width, height, &texels, scale as f32, axes).map_err(|e| match e {
            EnvMapError::NotRotation => Fail::at(p.loc_of("to_world"), format!("envmap: {e}")),
            _ => Fail::at(file_loc, format!("envmap \"{}\": {e}", path.display())),
        })
    }

    fn sensor(&mut self, idx: usize) -> Res<SensorSpec> {
        let obj = self.obj(idx)?;
        if obj.kind != "perspective" && obj.kind != "thinlens" {
            return Err(Fail::at(obj.loc, format!("unsupported sensor type \"{}\" (supported: perspective, thinlens)", obj.kind)));
        }
        self.check_children(obj, &[Tag::Film, Tag::Sampler])?;
        let film = self.single_child(obj, Tag::Film)?;
        let sampler = self.single_child(obj, Tag::Sampler)?;
        let mut p = Props::new(obj);
        let fov = p
            .float_opt("fov")?
            .ok_or_else(|| Fail::at(obj.loc, format!("the {} sensor needs `fov` (in degrees; `focal_length` is not supported)", obj.kind)))?;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(Fail::at(p.loc_of("fov"), format!("`fov` must be in (0, 180) degrees, got {fov}")));
        }
        let fov_axis = match p.string_opt("fov_axis")?.map(str::to_ascii_lowercase).as_deref() {
            None | Some("x") => FovAxis::X,
            Some("y") => FovAxis::Y,
            Some("smaller") => FovAxis::Smaller,
            Some("larger") => FovAxis::Larger,
            Some("diagonal") => FovAxis::Diagonal,
            Some(other) => {
                return Err(Fail::at(p.loc_of("fov_axis"), format!("unknown fov_axis \"{other}\" (supported: x, y, smaller, larger, diagonal)")));
            }
        };
        let to_world = self.render_frame * p.transform("to_world")?;
        match transform::similarity_scale(&to_world, 1e-3) {
            Some(s) if (s - 1.0).abs() <= 1e-3 => {}
            _ => {
                return Err(Fail::at(
                    p.loc_of("to_world"),
                    "the sensor's `to_world` must be a rotation and translation (use <lookat>); scale and shear are not supported",
                ));
            }
        }
        let far_clip = self.clip_planes(&mut p, obj)?;
        let lens = if obj.kind == "thinlens" { self.lens(&mut p, obj.loc, far_clip)? } else { None };
        p.finish()?;
        let (width, height, filter) = match film {
            Some(f) => self.film(f)?,
            None => {
                self.warnings.push(format!(
                    "line {}: the sensor has no <film>: using Mitsuba's default size {}×{} and gaussian filter",
                    self.line(obj.loc),
                    DEFAULT_FILM.0,
                    DEFAULT_FILM.1
                ));
                (DEFAULT_FILM.0, DEFAULT_FILM.1, Filter::MITSUBA_DEFAULT)
            }
        };
        let spp = match sampler {
            Some(s) => self.sampler(s)?,
            None => None,
        };
        Ok(SensorSpec { to_world, fov: fov as f32, fov_axis, width, height, spp, lens, filter })
    }

    /// Mitsuba's `near_clip` and `far_clip` (defaults 10⁻² and 10⁴), checked as Mitsuba
    /// checks them (0 < near < far); returns `far_clip`. Exported scenes nearly always
    /// give them, but ember's camera does not clip: its rays start at the camera and are
    /// unbounded (clipping would need a change to the core's camera), so geometry nearer
    /// than `near_clip` or beyond `far_clip` is visible where Mitsuba hides it. Given
    /// values are accepted with a warning that says so; `far_clip` is also `thinlens`'s
    /// default focus distance, as in Mitsuba.
    fn clip_planes(&mut self, p: &mut Props, obj: &Obj) -> Res<f64> {
        let near = p.float_opt("near_clip")?;
        let far = p.float_opt("far_clip")?;
        let (n, f) = (near.unwrap_or(1e-2), far.unwrap_or(1e4));
        if !(n > 0.0) {
            return Err(Fail::at(p.loc_of("near_clip"), format!("`near_clip` must be positive, got {n}")));
        }
        if !(n < f) {
            let at = if far.is_some() { "far_clip" } else { "near_clip" };
            return Err(Fail::at(p.loc_of(at), format!("`near_clip` ({n}) must be smaller than `far_clip` ({f})")));
        }
        if near.is_some() || far.is_some() {
            self.warnings.push(format!(
                "line {}: the sensor's near_clip {n} and far_clip {f} are accepted but not modelled: ember's camera does not clip, \
                 so geometry nearer than near_clip or beyond far_clip is visible (Mitsuba hides it)",
                self.line(obj.loc)
            ));
        }
        Ok(f)
    }

    /// `thinlens`'s `aperture_radius` (required, as in Mitsuba) and `focus_distance`
    /// (Mitsuba's default: `far_clip`). A zero aperture is the pinhole
    /// (Mitsuba substitutes its float epsilon, with a warning).
    fn lens(&mut self, p: &mut Props, loc: Loc, far_clip: f64) -> Res<Option<Lens>> {
        let radius = p.float_opt("aperture_radius")?.ok_or_else(|| Fail::at(loc, "the thinlens sensor needs `aperture_radius`"))?;
        if !(radius >= 0.0 && radius.is_finite()) {
            return Err(Fail::at(p.loc_of("aperture_radius"), format!("`aperture_radius` must be finite and non-negative, got {radius}")));
        }
        let focus = p.float_opt("focus_distance")?.unwrap_or(far_clip);
        if !(focus > 0.0 && focus.is_finite()) {
            return Err(Fail::at(p.loc_of("focus_distance"), format!("`focus_distance` must be finite and positive, got {focus}")));
        }
        if radius == 0.0 {
            self.warnings.push(format!("line {}: thinlens with a zero `aperture_radius`: rendered as a pinhole", self.line(loc)));
            return Ok(None);
        }
        Lens::new(radius as f32, focus as f32).map(Some).ok_or_else(|| Fail::at(p.loc_of("aperture_radius"), "the lens does not fit in single precision"))
    }

    fn film(&mut self, idx: usize) -> Res<(u32, u32, Filter)> {
        let obj = self.obj(idx)?;
        self.mark(idx);
        if obj.kind != "hdrfilm" {
            return Err(Fail::at(obj.loc, format!("unsupported film type \"{}\" (supported: hdrfilm)", obj.kind)));
        }
        self.check_children(obj, &[Tag::RFilter])?;
        let mut p = Props::new(obj);
        let width = film_side(&mut p, "width", DEFAULT_FILM.0)?;
        let height = film_side(&mut p, "height", DEFAULT_FILM.1)?;
        if let Some(f) = p.string_opt("file_format")?
            && f != "openexr"
            && f != "exr"
        {
            self.warnings.push(format!("line {}: film file_format \"{f}\" is not used: the command line chooses the output", self.line(obj.loc)));
        }
        if let Some(f) = p.string_opt("pixel_format")?
            && f != "rgb"
            && f != "rgba"
        {
            self.warnings.push(format!("line {}: film pixel_format \"{f}\" is not used: ember writes RGB", self.line(obj.loc)));
        }
        p.finish()?;
        // No <rfilter>: Mitsuba's default, the gaussian (`src/render/film.cpp`).
        let filter = match self.single_child(obj, Tag::RFilter)? {
            Some(r) => self.rfilter(r)?,
            None => Filter::MITSUBA_DEFAULT,
        };
        Ok((width, height, filter))
    }

    /// `box`, `tent` (`radius`, default 1) or `gaussian` (`stddev`, default 0.5).
    fn rfilter(&mut self, idx: usize) -> Res<Filter> {
        let rf = self.obj(idx)?;
        self.mark(idx);
        self.no_children(rf)?;
        let mut p = Props::new(rf);
        let (name, default) = match rf.kind.as_str() {
            "box" => ("", 0.0),
            "tent" => ("radius", 1.0),
            "gaussian" => ("stddev", 0.5),
            other => return Err(Fail::at(rf.loc, format!("unsupported rfilter type \"{other}\" (supported: box, tent, gaussian)"))),
        };
        let filter = if name.is_empty() {
            Filter::Box
        } else {
            let v = p.float_opt(name)?.unwrap_or(default);
            let f = if rf.kind == "tent" { Filter::tent(v as f32) } else { Filter::gaussian(v as f32) };
            f.ok_or_else(|| Fail::at(p.loc_of(name), format!("{} `{name}` must be finite and positive, got {v}", rf.kind)))?
        };
        p.finish()?;
        Ok(filter)
    }

    fn sampler(&mut self, idx: usize) -> Res<Option<u32>> {
        let obj = self.obj(idx)?;
        self.mark(idx);
        self.no_children(obj)?;
        let mut p = Props::new(obj);
        let spp = match p.int_opt("sample_count")? {
            Some(n) if n >= 1 && n <= u32::MAX as i64 => Some(n as u32),
            Some(n) => return Err(Fail::at(p.loc_of("sample_count"), format!("`sample_count` must be in 1..={}, got {n}", u32::MAX))),
            None => None,
        };
        p.finish()?;
        if obj.kind != "independent" {
            self.warnings.push(format!(
                "line {}: sampler type \"{}\" is not modelled: ember uses its own sampler (only sample_count is read)",
                self.line(obj.loc),
                obj.kind
            ));
        }
        Ok(spp)
    }

    fn integrator(&mut self, idx: usize) -> Res<Option<i32>> {
        let obj = self.obj(idx)?;
        self.no_children(obj)?;
        let mut p = Props::new(obj);
        let depth = match p.int_opt("max_depth")? {
            Some(d) if d >= -1 && d <= i32::MAX as i64 => Some(d as i32),
            Some(d) => {
                return Err(Fail::at(p.loc_of("max_depth"), format!("`max_depth` must be -1 (unbounded) or a non-negative integer, got {d}")));
            }
            None => None,
        };
        p.finish()?;
        if obj.kind == "volpath" {
            // The media ember models (absorption inside dielectric shapes) are rendered by
            // every estimator; a scattering medium is refused where it is declared.
            self.warnings.push(format!(
                "line {}: integrator \"volpath\" is rendered as \"path\" (PT unless the command line chooses another estimator): only absorbing media (albedo 0) are modelled",
                self.line(obj.loc)
            ));
        } else if obj.kind != "path" {
            self.warnings.push(format!(
                "line {}: integrator type \"{}\" is not used: the command line chooses the estimator (only max_depth is read)",
                self.line(obj.loc),
                obj.kind
            ));
        }
        Ok(depth)
    }
}

fn film_side(p: &mut Props, name: &'static str, default: u32) -> Res<u32> {
    match p.int_opt(name)? {
        None => Ok(default),
        Some(v) if (1..=MAX_FILM_SIDE).contains(&v) => Ok(v as u32),
        Some(v) => Err(Fail::at(p.loc_of(name), format!("film `{name}` must be in 1..={MAX_FILM_SIDE}, got {v}"))),
    }
}

/// Emitted quantities must be non-negative.
fn nonnegative(p: &Props, name: &str, c: Rgb) -> Res<Rgb> {
    if c.is_valid_radiance() { Ok(c) } else { Err(Fail::at(p.loc_of(name), format!("`{name}` must be non-negative, got ({}, {}, {})", c.r, c.g, c.b))) }
}
