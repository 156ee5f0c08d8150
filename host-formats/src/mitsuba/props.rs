//! Typed access to an object's properties, recording which ones its plugin read, so
//! that [`Props::finish`] can reject the rest as Mitsuba does ("unreferenced property").

use glam::DMat4;

use ember_core::spectrum::Rgb;

use super::xml::{Obj, Prop, Value};
use super::{Fail, Loc, Res};

/// A plugin's view of one object's properties.
#[derive(Debug)]
pub(crate) struct Props<'a> {
    obj: &'a Obj,
    used: Vec<bool>,
    /// Names the plugin asked for, for the error listing what it accepts.
    known: Vec<&'static str>,
}

impl<'a> Props<'a> {
    pub fn new(obj: &'a Obj) -> Self {
        Self { obj, used: vec![false; obj.props.len()], known: Vec::new() }
    }

    /// Find a property and mark it read.
    fn take(&mut self, name: &'static str) -> Option<&'a Prop> {
        if !self.known.contains(&name) {
            self.known.push(name);
        }
        let i = self.obj.props.iter().position(|p| p.name == name)?;
        self.used[i] = true;
        self.obj.props.get(i)
    }

    pub fn has(&self, name: &str) -> bool {
        self.obj.props.iter().any(|p| p.name == name)
    }

    /// The value tag of a property, if present (`"float"`, `"string"`, ...).
    pub fn value_tag(&self, name: &str) -> Option<&'static str> {
        self.obj.props.iter().find(|p| p.name == name).map(|p| p.value.tag_name())
    }

    /// Where a property is (or the object, when it is absent).
    pub fn loc_of(&self, name: &str) -> Loc {
        self.obj.props.iter().find(|p| p.name == name).map_or(self.obj.loc, |p| p.loc)
    }

    fn wrong_type(&self, p: &Prop, expected: &str) -> Fail {
        Fail::at(p.loc, format!("property `{}` of {} must be {expected}, not <{}>", p.name, self.obj.label(), p.value.tag_name()))
    }

    /// A `float` (an `integer` is accepted too).
    pub fn float_opt(&mut self, name: &'static str) -> Res<Option<f64>> {
        let Some(p) = self.take(name) else { return Ok(None) };
        match p.value {
            Value::Float(v) => Ok(Some(v)),
            Value::Integer(v) => Ok(Some(v as f64)),
            _ => Err(self.wrong_type(p, "a <float>")),
        }
    }

    pub fn float(&mut self, name: &'static str, default: f64) -> Res<f64> {
        Ok(self.float_opt(name)?.unwrap_or(default))
    }

    pub fn int_opt(&mut self, name: &'static str) -> Res<Option<i64>> {
        let Some(p) = self.take(name) else { return Ok(None) };
        match p.value {
            Value::Integer(v) => Ok(Some(v)),
            _ => Err(self.wrong_type(p, "an <integer>")),
        }
    }

    pub fn bool(&mut self, name: &'static str, default: bool) -> Res<bool> {
        let Some(p) = self.take(name) else { return Ok(default) };
        match p.value {
            Value::Boolean(v) => Ok(v),
            _ => Err(self.wrong_type(p, "a <boolean>")),
        }
    }

    pub fn string_opt(&mut self, name: &'static str) -> Res<Option<&'a str>> {
        let Some(p) = self.take(name) else { return Ok(None) };
        match &p.value {
            Value::String(s) => Ok(Some(s.as_str())),
            _ => Err(self.wrong_type(p, "a <string>")),
        }
    }

    /// A colour: `rgb`, `spectrum` (one value), `float` or `integer` (grey).
    pub fn color_opt(&mut self, name: &'static str) -> Res<Option<Rgb>> {
        let Some(p) = self.take(name) else { return Ok(None) };
        let v = match p.value {
            Value::Rgb(c) => c,
            Value::Spectrum(v) | Value::Float(v) => [v; 3],
            Value::Integer(v) => [v as f64; 3],
            _ => return Err(self.wrong_type(p, "a colour (<rgb>, <spectrum> or <float>)")),
        };
        Ok(Some(Rgb::new(v[0] as f32, v[1] as f32, v[2] as f32)))
    }

    pub fn color(&mut self, name: &'static str, default: Rgb) -> Res<Rgb> {
        Ok(self.color_opt(name)?.unwrap_or(default))
    }

    /// A position: `point` (or `vector`, which Mitsuba also accepts).
    pub fn point_opt(&mut self, name: &'static str) -> Res<Option<[f64; 3]>> {
        let Some(p) = self.take(name) else { return Ok(None) };
        match p.value {
            Value::Point(v) | Value::Vector(v) => Ok(Some(v)),
            _ => Err(self.wrong_type(p, "a <point>")),
        }
    }

    /// A direction: `vector` (or `point`).
    pub fn vector_opt(&mut self, name: &'static str) -> Res<Option<[f64; 3]>> {
        let Some(p) = self.take(name) else { return Ok(None) };
        match p.value {
            Value::Point(v) | Value::Vector(v) => Ok(Some(v)),
            _ => Err(self.wrong_type(p, "a <vector>")),
        }
    }

    pub fn transform_opt(&mut self, name: &'static str) -> Res<Option<DMat4>> {
        let Some(p) = self.take(name) else { return Ok(None) };
        match p.value {
            Value::Transform(m) => Ok(Some(m)),
            _ => Err(self.wrong_type(p, "a <transform>")),
        }
    }

    pub fn transform(&mut self, name: &'static str) -> Res<DMat4> {
        Ok(self.transform_opt(name)?.unwrap_or(DMat4::IDENTITY))
    }

    /// Error on the first property the plugin did not read.
    pub fn finish(self) -> Res<()> {
        for (p, used) in self.obj.props.iter().zip(&self.used) {
            if !used {
                let accepted = if self.known.is_empty() { "no properties".to_string() } else { self.known.join(", ") };
                return Err(Fail::at(p.loc, format!("unreferenced property `{}` in {} (it accepts: {accepted})", p.name, self.obj.label())));
            }
        }
        Ok(())
    }
}
