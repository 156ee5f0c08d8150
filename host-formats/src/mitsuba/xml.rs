//! First pass: XML text to a tree of plugin objects with typed, substituted properties.
//!
//! Nothing is instantiated here; the second pass ([`super::build`]) asks each object for
//! the properties its plugin knows and rejects the rest. This pass rejects what is
//! malformed whatever the plugin: unknown elements and attributes, numbers that do not
//! parse or are not finite, undefined `$parameters`, broken or duplicate ids.

use std::collections::HashMap;

use glam::DMat4;
use roxmltree::{Document, Node, ParsingOptions};

use super::positions::Positions;
use super::transform;
use super::{Fail, Loc, Res};

/// Objects nested deeper than this are rejected (the parser recurses).
const MAX_DEPTH: usize = 48;

/// The plugin categories (Mitsuba's object tags).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Tag {
    Bsdf,
    Shape,
    Emitter,
    Sensor,
    Film,
    RFilter,
    Sampler,
    Integrator,
    Texture,
    Medium,
}

impl Tag {
    fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "bsdf" => Self::Bsdf,
            "shape" => Self::Shape,
            "emitter" => Self::Emitter,
            "sensor" => Self::Sensor,
            "film" => Self::Film,
            "rfilter" => Self::RFilter,
            "sampler" => Self::Sampler,
            "integrator" => Self::Integrator,
            "texture" => Self::Texture,
            "medium" => Self::Medium,
            _ => return None,
        })
    }
    pub fn name(self) -> &'static str {
        match self {
            Self::Bsdf => "bsdf",
            Self::Shape => "shape",
            Self::Emitter => "emitter",
            Self::Sensor => "sensor",
            Self::Film => "film",
            Self::RFilter => "rfilter",
            Self::Sampler => "sampler",
            Self::Integrator => "integrator",
            Self::Texture => "texture",
            Self::Medium => "medium",
        }
    }
}

const OBJECT_TAGS: &str = "bsdf, shape, emitter, sensor, film, rfilter, sampler, integrator, texture, medium";
const VALUE_TAGS: &str = "float, integer, boolean, string, rgb, spectrum, point, vector, transform";

/// A typed property value.
#[derive(Clone, Debug)]
pub(crate) enum Value {
    Float(f64),
    Integer(i64),
    Boolean(bool),
    String(String),
    Rgb([f64; 3]),
    /// A constant spectrum (one value): grey.
    Spectrum(f64),
    Point([f64; 3]),
    Vector([f64; 3]),
    Transform(DMat4),
}

impl Value {
    pub fn tag_name(&self) -> &'static str {
        match self {
            Self::Float(_) => "float",
            Self::Integer(_) => "integer",
            Self::Boolean(_) => "boolean",
            Self::String(_) => "string",
            Self::Rgb(_) => "rgb",
            Self::Spectrum(_) => "spectrum",
            Self::Point(_) => "point",
            Self::Vector(_) => "vector",
            Self::Transform(_) => "transform",
        }
    }
}

/// A named property of an object.
#[derive(Clone, Debug)]
pub(crate) struct Prop {
    pub name: String,
    pub value: Value,
    /// The property element.
    pub loc: Loc,
}

/// A nested object (inline or through `ref`).
#[derive(Clone, Debug)]
pub(crate) struct Child {
    /// Index into [`Parsed::objs`].
    pub obj: usize,
    /// The nested element or the `ref` element.
    pub loc: Loc,
    /// Its `name` attribute: the parameter of the parent it sets (a texture's).
    pub name: Option<String>,
}

/// A plugin object.
#[derive(Clone, Debug)]
pub(crate) struct Obj {
    pub tag: Tag,
    /// The plugin type (`type` attribute, substituted).
    pub kind: String,
    pub id: Option<String>,
    pub loc: Loc,
    pub props: Vec<Prop>,
    pub children: Vec<Child>,
}

impl Obj {
    /// `<bsdf type="diffuse">`-style label for messages.
    pub fn label(&self) -> String {
        format!("<{} type=\"{}\">", self.tag.name(), self.kind)
    }
}

/// The parsed file.
#[derive(Debug, Default)]
pub(crate) struct Parsed {
    pub objs: Vec<Obj>,
    /// Objects directly inside `<scene>`, in document order.
    pub top: Vec<usize>,
    pub warnings: Vec<String>,
}

/// Parse the document of `positions`; `overrides` replace `<default>` values (`-D
/// name=value`).
pub(crate) fn parse(positions: &Positions, overrides: &[(String, String)]) -> Res<Parsed> {
    let text = positions.text();
    let opts = ParsingOptions { allow_dtd: false, ..ParsingOptions::default() };
    let doc = Document::parse_with_options(text, opts).map_err(|e| match e {
        // roxmltree places these at 1:1; the problem is where the text stops.
        roxmltree::Error::UnexpectedEndOfStream | roxmltree::Error::UnclosedRootNode => {
            Fail::at(positions.end(), format!("malformed XML: {e}: the text ends here with elements left open (is the file truncated?)"))
        }
        _ => {
            let p = e.pos();
            Fail::at(Loc::At { line: p.row, col: p.col }, format!("malformed XML: {e}"))
        }
    })?;
    let mut p = Parser {
        positions,
        params: HashMap::new(),
        overrides: overrides.iter().map(|(k, v)| (k.clone(), (v.clone(), false))).collect(),
        ids: HashMap::new(),
        out: Parsed::default(),
    };
    p.scene(doc.root_element())?;
    let mut unused: Vec<&String> = p.overrides.iter().filter(|(_, (_, used))| !used).map(|(k, _)| k).collect();
    unused.sort();
    for k in unused {
        p.out.warnings.push(format!("parameter `{k}` given on the command line is not used by the scene"));
    }
    Ok(p.out)
}

struct Parser<'a, 't> {
    /// The text's places, resolved into lines only for messages.
    positions: &'a Positions<'t>,
    /// `<default>` values.
    params: HashMap<String, String>,
    /// Caller overrides and whether a substitution used them.
    overrides: HashMap<String, (String, bool)>,
    /// id → (object, where it was declared).
    ids: HashMap<String, (usize, Loc)>,
    out: Parsed,
}

impl Parser<'_, '_> {
    /// Where `node` starts. Only an offset: [`Positions`] turns it into a line and column
    /// if a message shows it.
    fn loc(&self, node: Node) -> Loc {
        Loc::Offset(node.range().start)
    }

    /// Where attribute `name`'s value starts (the element, when it has none).
    fn attr_loc(&self, node: Node, name: &str) -> Loc {
        match node.attribute_node(name) {
            Some(a) => Loc::Offset(a.range_value().start),
            None => self.loc(node),
        }
    }

    /// Reject attributes other than `allowed`.
    fn check_attrs(&self, node: Node, allowed: &[&str]) -> Res<()> {
        for a in node.attributes() {
            if a.namespace().is_some() || !allowed.contains(&a.name()) {
                let what = if allowed.is_empty() { "no attributes".to_string() } else { allowed.join(", ") };
                return Err(Fail::at(
                    Loc::Offset(a.range().start),
                    format!("unexpected attribute `{}` on <{}> (allowed: {what})", a.name(), node.tag_name().name()),
                ));
            }
        }
        Ok(())
    }

    /// An attribute's value after `$name` substitution. A value that takes a `-D`
    /// override is noted at the attribute and its element, for the messages about it.
    fn attr(&mut self, node: Node, name: &str) -> Res<Option<String>> {
        match node.attribute(name) {
            Some(raw) => {
                let loc = self.attr_loc(node, name);
                let mut given = Vec::new();
                let value = self.substitute(raw, loc, &mut given)?;
                for g in &given {
                    self.positions.note_override(loc, g);
                    self.positions.note_override(self.loc(node), g);
                }
                Ok(Some(value))
            }
            None => Ok(None),
        }
    }

    fn required_attr(&mut self, node: Node, name: &str) -> Res<String> {
        let loc = self.loc(node);
        self.attr(node, name)?.ok_or_else(|| Fail::at(loc, format!("<{}> needs a `{name}` attribute", node.tag_name().name())))
    }

    /// Replace `$name` and `${name}` by the parameter's value (overrides first, then
    /// `<default>`s). A `$` not followed by a name is kept. The overrides used are
    /// pushed to `given` as `name=value`.
    fn substitute(&mut self, raw: &str, loc: Loc, given: &mut Vec<String>) -> Res<String> {
        if !raw.contains('$') {
            return Ok(raw.to_string());
        }
        let mut out = String::with_capacity(raw.len());
        let mut rest = raw;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            let (name, consumed) = if let Some(braced) = after.strip_prefix('{') {
                match braced.find('}') {
                    Some(end) => (&braced[..end], end + 2),
                    None => return Err(Fail::at(loc, format!("unclosed `${{` in \"{raw}\""))),
                }
            } else {
                let end = after.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(after.len());
                (&after[..end], end)
            };
            if name.is_empty() {
                out.push('$');
                rest = after;
                continue;
            }
            let value = if let Some((v, used)) = self.overrides.get_mut(name) {
                *used = true;
                given.push(format!("{name}={v}"));
                v.clone()
            } else if let Some(v) = self.params.get(name) {
                v.clone()
            } else {
                return Err(Fail::at(
                    loc,
                    format!("undefined parameter `${name}` (declare it with <default name=\"{name}\" value=\"...\"/> before use, or pass it with -D)"),
                ));
            };
            out.push_str(&value);
            rest = &after[consumed..];
        }
        out.push_str(rest);
        Ok(out)
    }

    fn scene(&mut self, root: Node) -> Res<()> {
        let loc = self.loc(root);
        if root.tag_name().name() != "scene" || root.tag_name().namespace().is_some() {
            return Err(Fail::at(loc, format!("the root element is <{}>; a Mitsuba scene file starts with <scene version=\"3.0.0\">", root.tag_name().name())));
        }
        self.check_attrs(root, &["version"])?;
        let version = self.attr(root, "version")?.ok_or_else(|| Fail::at(loc, "<scene> needs a `version` attribute (e.g. version=\"3.0.0\")"))?;
        let major = version.split('.').next().unwrap_or("");
        if major != "2" && major != "3" {
            return Err(Fail::at(self.attr_loc(root, "version"), format!("scene version \"{version}\" is not supported (2.x and 3.x are)")));
        }
        for child in root.children() {
            let Some(elem) = self.element(child)? else { continue };
            let name = elem.tag_name().name();
            if name == "default" {
                self.default(elem)?;
            } else if let Some(tag) = Tag::from_name(name) {
                let idx = self.object(elem, tag, 0)?;
                self.out.top.push(idx);
            } else {
                let what = if is_value_tag(name) || name == "ref" {
                    format!("<{name}> cannot appear directly inside <scene>")
                } else {
                    format!("unsupported element <{name}>")
                };
                return Err(Fail::at(self.loc(elem), format!("{what}; <scene> accepts: default, {OBJECT_TAGS}")));
            }
        }
        Ok(())
    }

    /// The element in `node`, `None` for comments and whitespace; other text is an error.
    fn element<'n, 'input>(&self, node: Node<'n, 'input>) -> Res<Option<Node<'n, 'input>>> {
        if node.is_element() {
            if node.tag_name().namespace().is_some() {
                return Err(Fail::at(self.loc(node), format!("namespaced element <{}> is not supported", node.tag_name().name())));
            }
            return Ok(Some(node));
        }
        if node.is_text() && node.text().is_some_and(|t| !t.trim().is_empty()) {
            return Err(Fail::at(self.loc(node), "unexpected text (only elements, comments and whitespace are allowed)"));
        }
        Ok(None)
    }

    fn default(&mut self, node: Node) -> Res<()> {
        self.check_attrs(node, &["name", "value"])?;
        self.no_children(node)?;
        let loc = self.loc(node);
        let name = node.attribute("name").ok_or_else(|| Fail::at(loc, "<default> needs a `name` attribute"))?;
        let value = node.attribute("value").ok_or_else(|| Fail::at(loc, "<default> needs a `value` attribute"))?;
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(Fail::at(self.attr_loc(node, "name"), format!("parameter name \"{name}\" must be letters, digits and `_`")));
        }
        if self.params.insert(name.to_string(), value.to_string()).is_some() {
            return Err(Fail::at(loc, format!("parameter `{name}` is declared twice")));
        }
        Ok(())
    }

    fn no_children(&self, node: Node) -> Res<()> {
        for c in node.children() {
            if let Some(e) = self.element(c)? {
                return Err(Fail::at(self.loc(e), format!("<{}> cannot contain <{}>", node.tag_name().name(), e.tag_name().name())));
            }
        }
        Ok(())
    }

    /// Parse a plugin object and its contents; returns its index.
    fn object(&mut self, node: Node, tag: Tag, depth: usize) -> Res<usize> {
        let loc = self.loc(node);
        if depth > MAX_DEPTH {
            return Err(Fail::at(loc, format!("objects are nested more than {MAX_DEPTH} deep")));
        }
        self.check_attrs(node, &["type", "id", "name"])?;
        let kind = self.required_attr(node, "type")?;
        let id = self.attr(node, "id")?;
        // `name` is the parameter of the parent it sets: the parent reads it from the
        // `Child` (textures need it; other plugins take nested objects by category).
        let mut obj = Obj { tag, kind, id: id.clone(), loc, props: Vec::new(), children: Vec::new() };
        for child in node.children() {
            let Some(elem) = self.element(child)? else { continue };
            let name = elem.tag_name().name();
            if let Some(child_tag) = Tag::from_name(name) {
                let name = self.attr(elem, "name")?;
                let idx = self.object(elem, child_tag, depth + 1)?;
                obj.children.push(Child { obj: idx, loc: self.loc(elem), name });
            } else if name == "ref" {
                obj.children.push(self.reference(elem)?);
            } else if is_value_tag(name) {
                let prop = self.property(elem)?;
                if let Some(prev) = obj.props.iter().find(|p| p.name == prop.name) {
                    return Err(Fail::at(
                        prop.loc,
                        format!("property `{}` is given twice in {} (first at line {})", prop.name, obj.label(), self.positions.line(prev.loc)),
                    ));
                }
                obj.props.push(prop);
            } else {
                return Err(Fail::at(self.loc(elem), format!("unsupported element <{name}> in {}; allowed: {VALUE_TAGS}, ref, {OBJECT_TAGS}", obj.label())));
            }
        }
        let idx = self.out.objs.len();
        self.out.objs.push(obj);
        if let Some(id) = id {
            if let Some((_, prev)) = self.ids.get(&id) {
                return Err(Fail::at(self.attr_loc(node, "id"), format!("id \"{id}\" is already used at line {}", self.positions.line(*prev))));
            }
            self.ids.insert(id, (idx, loc));
        }
        Ok(idx)
    }

    fn reference(&mut self, node: Node) -> Res<Child> {
        self.check_attrs(node, &["id", "name"])?;
        self.no_children(node)?;
        let loc = self.loc(node);
        let id = self.required_attr(node, "id")?;
        let name = self.attr(node, "name")?;
        match self.ids.get(&id) {
            Some(&(obj, _)) => Ok(Child { obj, loc, name }),
            None => Err(Fail::at(
                self.attr_loc(node, "id"),
                format!("reference to unknown id \"{id}\" (an object must be declared with this id before it is referenced)"),
            )),
        }
    }

    fn property(&mut self, node: Node) -> Res<Prop> {
        let tag = node.tag_name().name();
        let loc = self.loc(node);
        if tag == "transform" {
            self.check_attrs(node, &["name"])?;
            let name = self.required_attr(node, "name")?;
            let mut m = DMat4::IDENTITY;
            for child in node.children() {
                let Some(elem) = self.element(child)? else { continue };
                self.no_children(elem)?;
                let op = self.transform_op(elem)?;
                m = op * m;
            }
            return Ok(Prop { name, value: Value::Transform(m), loc });
        }
        self.no_children(node)?;
        let value = match tag {
            "point" | "vector" => {
                self.check_attrs(node, &["name", "value", "x", "y", "z"])?;
                let v = self.xyz(node, 0.0)?;
                if tag == "point" { Value::Point(v) } else { Value::Vector(v) }
            }
            _ => {
                self.check_attrs(node, &["name", "value"])?;
                let raw = self.required_attr(node, "value")?;
                let vloc = self.attr_loc(node, "value");
                match tag {
                    "float" => Value::Float(parse_float(&raw, vloc)?),
                    "integer" => Value::Integer(raw.trim().parse::<i64>().map_err(|_| Fail::at(vloc, format!("malformed integer \"{raw}\"")))?),
                    "boolean" => match raw.trim().to_ascii_lowercase().as_str() {
                        "true" => Value::Boolean(true),
                        "false" => Value::Boolean(false),
                        _ => return Err(Fail::at(vloc, format!("malformed boolean \"{raw}\" (use true or false)"))),
                    },
                    "string" => Value::String(raw),
                    "rgb" => {
                        let v = parse_list(&raw, vloc)?;
                        match v[..] {
                            [g] => Value::Rgb([g; 3]),
                            [r, g, b] => Value::Rgb([r, g, b]),
                            _ => return Err(Fail::at(vloc, format!("<rgb> needs 1 or 3 values, got {} in \"{raw}\"", v.len()))),
                        }
                    }
                    "spectrum" => {
                        if raw.contains(':') {
                            return Err(Fail::at(vloc, "wavelength:value spectra are not supported; give one value (a grey spectrum) or use <rgb>"));
                        }
                        match parse_list(&raw, vloc)?[..] {
                            [v] => Value::Spectrum(v),
                            _ => {
                                return Err(Fail::at(vloc, format!("<spectrum> needs exactly one value (a grey spectrum), got \"{raw}\"")));
                            }
                        }
                    }
                    _ => unsupported_value_tag(tag, loc)?,
                }
            }
        };
        let name = self.required_attr(node, "name")?;
        Ok(Prop { name, value, loc })
    }

    /// `x`, `y`, `z` attributes (missing ones = `default`) or `value="x y z"`.
    fn xyz(&mut self, node: Node, default: f64) -> Res<[f64; 3]> {
        let has_xyz = ["x", "y", "z"].iter().any(|a| node.attribute(*a).is_some());
        if let Some(raw) = self.attr(node, "value")? {
            let vloc = self.attr_loc(node, "value");
            if has_xyz {
                return Err(Fail::at(vloc, format!("<{}>: give either `value` or `x`/`y`/`z`, not both", node.tag_name().name())));
            }
            let v = parse_list(&raw, vloc)?;
            return match v[..] {
                [x, y, z] => Ok([x, y, z]),
                _ => Err(Fail::at(vloc, format!("<{}> `value` needs 3 numbers, got \"{raw}\"", node.tag_name().name()))),
            };
        }
        let mut out = [default; 3];
        for (i, a) in ["x", "y", "z"].iter().enumerate() {
            if let Some(raw) = self.attr(node, a)? {
                out[i] = parse_float(&raw, self.attr_loc(node, a))?;
            }
        }
        Ok(out)
    }

    /// One child of `<transform>` as a matrix.
    fn transform_op(&mut self, node: Node) -> Res<DMat4> {
        let loc = self.loc(node);
        let m = match node.tag_name().name() {
            "translate" => {
                self.check_attrs(node, &["x", "y", "z", "value"])?;
                transform::translate(self.xyz(node, 0.0)?)
            }
            "scale" => {
                self.check_attrs(node, &["x", "y", "z", "value"])?;
                let has_xyz = ["x", "y", "z"].iter().any(|a| node.attribute(*a).is_some());
                match self.attr(node, "value")? {
                    Some(raw) if !has_xyz => {
                        let vloc = self.attr_loc(node, "value");
                        match parse_list(&raw, vloc)?[..] {
                            [s] => transform::scale([s; 3]),
                            [x, y, z] => transform::scale([x, y, z]),
                            _ => return Err(Fail::at(vloc, format!("<scale> `value` needs 1 or 3 numbers, got \"{raw}\""))),
                        }
                    }
                    _ => transform::scale(self.xyz(node, 1.0)?),
                }
            }
            "rotate" => {
                self.check_attrs(node, &["x", "y", "z", "value", "angle"])?;
                let raw = self.required_attr(node, "angle")?;
                let angle = parse_float(&raw, self.attr_loc(node, "angle"))?;
                let axis = self.xyz(node, 0.0)?;
                transform::rotate(axis, angle).ok_or_else(|| Fail::at(loc, "<rotate> needs a non-zero axis (x, y, z or value)"))?
            }
            "matrix" => {
                self.check_attrs(node, &["value"])?;
                let raw = self.required_attr(node, "value")?;
                let vloc = self.attr_loc(node, "value");
                let v = parse_list(&raw, vloc)?;
                let arr: [f64; 16] =
                    v.try_into().map_err(|v: Vec<f64>| Fail::at(vloc, format!("<matrix> needs 16 values (row-major 4×4), got {}", v.len())))?;
                DMat4::from_cols_array(&arr).transpose()
            }
            "lookat" => {
                self.check_attrs(node, &["origin", "target", "up"])?;
                let get = |p: &mut Self, a: &str| -> Res<[f64; 3]> {
                    let raw = p.required_attr(node, a)?;
                    let vloc = p.attr_loc(node, a);
                    match parse_list(&raw, vloc)?[..] {
                        [x, y, z] => Ok([x, y, z]),
                        _ => Err(Fail::at(vloc, format!("<lookat> `{a}` needs 3 numbers, got \"{raw}\""))),
                    }
                };
                let origin = get(self, "origin")?;
                let target = get(self, "target")?;
                let up = get(self, "up")?;
                transform::look_at(origin, target, up).map_err(|m| Fail::at(loc, m))?
            }
            other => {
                return Err(Fail::at(loc, format!("unsupported transform <{other}>; allowed: translate, rotate, scale, matrix, lookat")));
            }
        };
        if !m.is_finite() || !m.as_mat4().is_finite() {
            return Err(Fail::at(loc, "this transform overflows single precision"));
        }
        Ok(m)
    }
}

fn unsupported_value_tag(tag: &str, loc: Loc) -> Res<Value> {
    Err(Fail::at(loc, format!("unsupported value tag <{tag}>")))
}

fn is_value_tag(name: &str) -> bool {
    matches!(name, "float" | "integer" | "boolean" | "string" | "rgb" | "spectrum" | "point" | "vector" | "transform")
}

/// A finite number that also fits an `f32`.
pub(crate) fn parse_float(raw: &str, loc: Loc) -> Res<f64> {
    let t = raw.trim();
    let v: f64 = t.parse().map_err(|_| Fail::at(loc, format!("malformed number \"{raw}\"")))?;
    // Rust also parses "inf" and "NaN": Mitsuba files never need them.
    if !v.is_finite() || !(v as f32).is_finite() {
        return Err(Fail::at(loc, format!("number \"{raw}\" is not finite in single precision")));
    }
    Ok(v)
}

/// Numbers separated by commas and/or whitespace.
pub(crate) fn parse_list(raw: &str, loc: Loc) -> Res<Vec<f64>> {
    raw.split(|c: char| c == ',' || c.is_whitespace()).filter(|s| !s.is_empty()).map(|s| parse_float(s, loc)).collect()
}
