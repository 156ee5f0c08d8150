//! Participating media in shapes: Mitsuba's `homogeneous` medium as a shape's
//! `interior`, read when it only absorbs (albedo 0: coloured glass, Bitterli's scenes).
//!
//! ember renders no scattering inside volumes, so a medium that scatters (albedo above
//! 0 in any channel, Mitsuba's default 0.75 included) is refused where it is declared,
//! and so are an `exterior` medium (ember's camera and lights sit in vacuum) and other
//! medium types. An absorbing one becomes σ_t = `sigma_t` · `scale` per unit of scene
//! length on the shape's material (`SceneBuilder::add_interior`): the estimators multiply
//! every segment inside by exp(−σ_t d) (`ember_core::scene`'s media notes). Mitsuba's
//! `sample_emitters` and `has_spectral_extinction` are read and change nothing here
//! (no scattering, RGB extinction).
//!
//! A medium must hold nothing but its own boundary: the camera, a point or spot light,
//! or another shape inside it or crossing it (nested media among them) is refused once
//! the scene is read ([`Placed::refuse_intrusion`], by `SceneBuilder::medium_intrusion`),
//! naming the line of the thing inside and of the shape whose medium it is in. So is a
//! sensor's or emitter's `medium` (Mitsuba's way to say where they sit).

use ember_core::geometry::MaterialId;
use ember_core::scene::{MediumIntruder, SceneBuilder};
use ember_core::spectrum::Rgb;

use super::Loc;
use super::build::{Ctx, Placed};
use super::props::Props;
use super::xml::{Obj, Tag};
use super::{Fail, Res};

impl Ctx<'_> {
    /// σ_t of the medium `obj` (a shape) declares as its interior, if any; every other
    /// medium is refused by file and line.
    pub(crate) fn interior_medium(&mut self, obj: &Obj) -> Res<Option<Rgb>> {
        let mut found: Option<Rgb> = None;
        for c in &obj.children {
            let medium = self.obj(c.obj)?;
            if medium.tag != Tag::Medium {
                continue;
            }
            self.mark(c.obj);
            match c.name.as_deref() {
                Some("interior") => {}
                Some("exterior") => {
                    return Err(Fail::at(
                        c.loc,
                        "an `exterior` medium is not supported: ember's camera and lights are in vacuum (only a shape's absorbing `interior` is)",
                    ));
                }
                Some(other) => return Err(Fail::at(c.loc, format!("a shape's medium is named \"{other}\" (supported: interior)"))),
                None => return Err(Fail::at(c.loc, "a shape's <medium> needs name=\"interior\"")),
            }
            if found.is_some() {
                return Err(Fail::at(c.loc, format!("{} takes at most one interior <medium>", obj.label())));
            }
            found = Some(self.absorbing_medium(c.obj)?);
        }
        Ok(found)
    }

    /// A `homogeneous` medium with albedo 0: its σ_t · scale.
    fn absorbing_medium(&mut self, idx: usize) -> Res<Rgb> {
        let obj = self.obj(idx)?;
        if obj.kind != "homogeneous" {
            return Err(Fail::at(obj.loc, format!("unsupported medium type \"{}\" (supported: homogeneous, with albedo 0)", obj.kind)));
        }
        self.check_children(obj, &[])?;
        let mut p = Props::new(obj);
        let albedo_loc = if p.has("albedo") { p.loc_of("albedo") } else { obj.loc };
        // Mitsuba's default albedo is 0.75: a medium that does not say scatters.
        let albedo = p.color("albedo", Rgb::splat(0.75))?;
        if albedo != Rgb::ZERO {
            return Err(Fail::at(
                albedo_loc,
                format!(
                    "a scattering medium (albedo ({}, {}, {})) is not supported: ember renders absorbing media only (albedo 0, the default is 0.75)",
                    albedo.r, albedo.g, albedo.b
                ),
            ));
        }
        let sigma_t = p.color("sigma_t", Rgb::ONE)?;
        if !(sigma_t.r >= 0.0 && sigma_t.g >= 0.0 && sigma_t.b >= 0.0 && sigma_t.is_finite()) {
            return Err(Fail::at(p.loc_of("sigma_t"), format!("`sigma_t` must be non-negative and finite, got ({}, {}, {})", sigma_t.r, sigma_t.g, sigma_t.b)));
        }
        let scale = p.float("scale", 1.0)?;
        if !(scale >= 0.0 && scale.is_finite()) {
            return Err(Fail::at(p.loc_of("scale"), format!("`scale` must be non-negative and finite, got {scale}")));
        }
        let _ = p.bool("sample_emitters", true)?;
        let _ = p.bool("has_spectral_extinction", true)?;
        p.finish()?;
        let sigma = sigma_t * scale as f32;
        if !sigma.is_finite() {
            return Err(Fail::at(obj.loc, "`sigma_t` · `scale` overflows"));
        }
        Ok(sigma)
    }
}

impl Placed {
    /// The object at `loc` has just been added to `sb`.
    pub(crate) fn record(&mut self, sb: &SceneBuilder, loc: Loc) {
        let g = sb.geometry();
        self.ends.push((g.triangles.len(), g.spheres.len(), sb.light_count(), loc));
    }

    /// The object that added the `i`-th item counted by `count`.
    fn owner(&self, i: usize, count: impl Fn(&(usize, usize, usize, Loc)) -> usize) -> Option<Loc> {
        self.ends.iter().find(|e| count(e) > i).map(|e| e.3)
    }

    /// The error for `what` inside the medium of material `medium`: at the intruder's
    /// line, naming the medium shape's.
    pub(crate) fn refuse_intrusion(&self, ctx: &Ctx, medium: MaterialId, what: MediumIntruder, sensor: Option<Loc>) -> Fail {
        let g = ctx.sb.geometry();
        let shape = match g.triangles.iter().position(|t| t.material == medium) {
            Some(i) => self.owner(i, |e| e.0),
            None => g.spheres.iter().position(|s| s.material == medium).and_then(|i| self.owner(i, |e| e.1)),
        };
        let (loc, thing) = match what {
            MediumIntruder::Camera => (sensor, "the sensor's position"),
            MediumIntruder::Light(l) => (self.owner(l as usize, |e| e.2), "this light"),
            MediumIntruder::Triangle(t) => (self.owner(t as usize, |e| e.0), "this shape"),
            MediumIntruder::Sphere(s) => (self.owner(s as usize, |e| e.1), "this sphere"),
        };
        let medium_at = shape.map_or_else(String::new, |l| format!(" of the shape at line {}", ctx.line(l)));
        let message = format!(
            "{thing} is inside (or crosses) the absorbing medium{medium_at}: ember attenuates a segment by the medium surface it ends on, which is right only when the medium holds nothing but its own boundary (no camera, light or other shape inside, no nested media)"
        );
        match loc.or(shape) {
            Some(l) => Fail::at(l, message),
            None => Fail::nowhere(message),
        }
    }
}
