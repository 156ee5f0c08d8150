//! A small PLY reader (Turk's Stanford polygon format): `ascii`, `binary_little_endian`
//! and `binary_big_endian`; the `vertex` element's `x y z` and optional `nx ny nz`, and
//! the `face` element's `vertex_indices` (or `vertex_index`) list, polygons triangulated
//! as fans. Other properties and elements are read past and reported in
//! [`MeshData::notes`]. Every read is bounds-checked: malformed input is an error.

use glam::{Vec2, Vec3};

use super::mesh::MeshData;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    BinaryLe,
    BinaryBe,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }
    fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }
}

#[derive(Clone, Debug)]
enum PropKind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
struct PropDef {
    name: String,
    kind: PropKind,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<PropDef>,
}

/// Where values come from.
enum Source<'a> {
    Ascii { tokens: AsciiTokens<'a>, line: usize },
    Binary { data: &'a [u8], pos: usize, big_endian: bool },
}

/// Whitespace-separated tokens with their 1-based line numbers.
struct AsciiTokens<'a> {
    text: &'a str,
    line: usize,
}

impl<'a> Iterator for AsciiTokens<'a> {
    type Item = (&'a str, usize);
    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let c = self.text.chars().next()?;
            if c == '\n' {
                self.line += 1;
            }
            if !c.is_whitespace() {
                break;
            }
            self.text = &self.text[c.len_utf8()..];
        }
        let end = self.text.find(char::is_whitespace).unwrap_or(self.text.len());
        let (tok, rest) = self.text.split_at(end);
        self.text = rest;
        Some((tok, self.line))
    }
}

impl Source<'_> {
    fn read(&mut self, t: Scalar) -> Result<f64, String> {
        match self {
            Self::Ascii { tokens, line } => {
                let (tok, l) = tokens.next().ok_or_else(|| format!("unexpected end of data after line {line}"))?;
                *line = l;
                let v = if t.is_integer() {
                    tok.parse::<i64>().map(|v| v as f64).map_err(|_| format!("line {l}: malformed integer \"{tok}\""))?
                } else {
                    tok.parse::<f64>().map_err(|_| format!("line {l}: malformed number \"{tok}\""))?
                };
                Ok(v)
            }
            Self::Binary { data, pos, big_endian } => {
                let n = t.size();
                let bytes = data.get(*pos..*pos + n).ok_or_else(|| format!("unexpected end of data at byte {pos}"))?;
                *pos += n;
                let mut b = [0u8; 8];
                b[..n].copy_from_slice(bytes);
                if *big_endian {
                    b[..n].reverse();
                }
                Ok(match t {
                    Scalar::I8 => b[0] as i8 as f64,
                    Scalar::U8 => b[0] as f64,
                    Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
                    Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
                    Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Scalar::F64 => f64::from_le_bytes(b),
                })
            }
        }
    }

    /// An index or count: a non-negative integer that fits `u32`.
    fn read_index(&mut self, t: Scalar, what: &str) -> Result<u32, String> {
        let v = self.read(t)?;
        if v.fract() == 0.0 && (0.0..=u32::MAX as f64).contains(&v) { Ok(v as u32) } else { Err(format!("invalid {what} {v}")) }
    }
}

/// Parse a PLY file's bytes.
pub(crate) fn parse(bytes: &[u8]) -> Result<MeshData, String> {
    let (format, elements, body) = header(bytes)?;
    let mut src = match format {
        Format::Ascii => {
            let text = std::str::from_utf8(body).map_err(|_| "the ascii body is not valid text")?;
            let header_lines = bytes.len().saturating_sub(body.len());
            let first_line = bytes.get(..header_lines).map_or(1, |h| h.iter().filter(|&&c| c == b'\n').count() + 1);
            Source::Ascii { tokens: AsciiTokens { text, line: first_line }, line: first_line }
        }
        Format::BinaryLe | Format::BinaryBe => Source::Binary { data: body, pos: 0, big_endian: format == Format::BinaryBe },
    };
    let mut out = MeshData::default();
    let mut normals: Vec<Vec3> = Vec::new();
    let mut texcoords: Vec<Vec2> = Vec::new();
    let mut polygon = Vec::new();
    let mut faces_seen = false;
    for el in &elements {
        if el.props.is_empty() {
            continue;
        }
        match el.name.as_str() {
            "vertex" => {
                let idx = |n: &str| el.props.iter().position(|p| p.name == n && matches!(p.kind, PropKind::Scalar(_)));
                let (Some(x), Some(y), Some(z)) = (idx("x"), idx("y"), idx("z")) else {
                    return Err("the vertex element needs scalar x, y and z properties".into());
                };
                let n = match (idx("nx"), idx("ny"), idx("nz")) {
                    (Some(a), Some(b), Some(c)) => Some([a, b, c]),
                    (None, None, None) => None,
                    _ => return Err("the vertex element has some but not all of nx, ny, nz".into()),
                };
                // Mitsuba's names for texture coordinates, in its order of preference.
                let uv = [("u", "v"), ("texture_u", "texture_v"), ("s", "t"), ("texture_s", "texture_t")].iter().find_map(|&(a, b)| Some([idx(a)?, idx(b)?]));
                let used = |i: usize| [x, y, z].contains(&i) || n.is_some_and(|n| n.contains(&i)) || uv.is_some_and(|t| t.contains(&i));
                let unused: Vec<&str> = el.props.iter().enumerate().filter(|(i, _)| !used(*i)).map(|(_, p)| p.name.as_str()).collect();
                if !unused.is_empty() {
                    out.notes.push(format!("vertex properties not used: {}", unused.join(", ")));
                }
                let mut vals = vec![0.0f64; el.props.len()];
                for _ in 0..el.count {
                    for (i, p) in el.props.iter().enumerate() {
                        vals[i] = read_prop(&mut src, p, &mut polygon)?;
                    }
                    out.positions.push(Vec3::new(vals[x] as f32, vals[y] as f32, vals[z] as f32));
                    if let Some([a, b, c]) = n {
                        normals.push(Vec3::new(vals[a] as f32, vals[b] as f32, vals[c] as f32));
                    }
                    if let Some([a, b]) = uv {
                        texcoords.push(Vec2::new(vals[a] as f32, vals[b] as f32));
                    }
                }
                if n.is_some() {
                    out.normals = Some(std::mem::take(&mut normals));
                }
                if uv.is_some() {
                    out.texcoords = Some(std::mem::take(&mut texcoords));
                }
            }
            "face" => {
                faces_seen = true;
                let list = el
                    .props
                    .iter()
                    .position(|p| (p.name == "vertex_indices" || p.name == "vertex_index") && matches!(p.kind, PropKind::List { .. }))
                    .ok_or("the face element needs a vertex_indices list")?;
                if el.props.len() > 1 {
                    let others: Vec<&str> = el.props.iter().enumerate().filter(|(i, _)| *i != list).map(|(_, p)| p.name.as_str()).collect();
                    out.notes.push(format!("face properties not used: {}", others.join(", ")));
                }
                let mut indices = Vec::new();
                for f in 0..el.count {
                    for (i, p) in el.props.iter().enumerate() {
                        let target = if i == list { &mut indices } else { &mut polygon };
                        read_prop(&mut src, p, target)?;
                    }
                    if indices.len() < 3 {
                        return Err(format!("face {f} has {} vertices (at least 3 are needed)", indices.len()));
                    }
                    for k in 1..indices.len() - 1 {
                        out.triangles.push([indices[0], indices[k], indices[k + 1]]);
                    }
                }
            }
            other => {
                out.notes.push(format!("element \"{other}\" not used"));
                for _ in 0..el.count {
                    for p in &el.props {
                        read_prop(&mut src, p, &mut polygon)?;
                    }
                }
            }
        }
    }
    let trailing = match &mut src {
        Source::Ascii { tokens, .. } => tokens.next().is_some(),
        Source::Binary { data, pos, .. } => *pos < data.len(),
    };
    if trailing {
        out.notes.push("data after the last element not used".into());
    }
    if !faces_seen {
        return Err("the file has no face element (point clouds are not supported)".into());
    }
    let n = out.positions.len();
    if let Some(bad) = out.triangles.iter().flatten().find(|&&i| i as usize >= n) {
        return Err(format!("face index {bad} out of range ({n} vertices)"));
    }
    Ok(out)
}

/// Read one property; a list's items go to `list` (as indices), a scalar is returned.
fn read_prop(src: &mut Source, p: &PropDef, list: &mut Vec<u32>) -> Result<f64, String> {
    match p.kind {
        PropKind::Scalar(t) => src.read(t),
        PropKind::List { count, item } => {
            let n = src.read_index(count, "list length")?;
            list.clear();
            for _ in 0..n {
                list.push(src.read_index(item, "vertex index")?);
            }
            Ok(n as f64)
        }
    }
}

/// Parse the header: format, elements, and the body that follows `end_header`.
fn header(bytes: &[u8]) -> Result<(Format, Vec<Element>, &[u8]), String> {
    let mut pos = 0;
    let mut next_line = || -> Result<&str, String> {
        let rest = bytes.get(pos..).unwrap_or_default();
        let end = rest.iter().position(|&c| c == b'\n').ok_or("the header does not end with end_header")?;
        let line = rest.get(..end).unwrap_or_default();
        pos += end + 1;
        let line = std::str::from_utf8(line).map_err(|_| "the header is not text")?;
        Ok(line.trim_end_matches('\r'))
    };
    if next_line()?.trim() != "ply" {
        return Err("not a PLY file (the first line is not \"ply\")".into());
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let line = next_line()?;
        let mut words = line.split_whitespace();
        match words.next() {
            None | Some("comment") | Some("obj_info") => {}
            Some("format") => {
                format = Some(match (words.next(), words.next()) {
                    (Some("ascii"), Some("1.0")) => Format::Ascii,
                    (Some("binary_little_endian"), Some("1.0")) => Format::BinaryLe,
                    (Some("binary_big_endian"), Some("1.0")) => Format::BinaryBe,
                    _ => return Err(format!("unsupported format line \"{line}\"")),
                });
            }
            Some("element") => {
                let (Some(name), Some(count), None) = (words.next(), words.next(), words.next()) else {
                    return Err(format!("malformed element line \"{line}\""));
                };
                let count = count.parse::<u64>().map_err(|_| format!("malformed element count in \"{line}\""))?;
                elements.push(Element { name: name.to_string(), count, props: Vec::new() });
            }
            Some("property") => {
                let el = elements.last_mut().ok_or("a property appears before any element")?;
                let parts: Vec<&str> = words.collect();
                let kind = match parts[..] {
                    ["list", c, i, _] => {
                        let count = Scalar::parse(c).filter(|s| s.is_integer());
                        let item = Scalar::parse(i).filter(|s| s.is_integer());
                        match (count, item) {
                            (Some(count), Some(item)) => PropKind::List { count, item },
                            _ => return Err(format!("unsupported list types in \"{line}\"")),
                        }
                    }
                    [t, _] => PropKind::Scalar(Scalar::parse(t).ok_or_else(|| format!("unknown type in \"{line}\""))?),
                    _ => return Err(format!("malformed property line \"{line}\"")),
                };
                let name = parts.last().map(|s| s.to_string()).unwrap_or_default();
                el.props.push(PropDef { name, kind });
            }
            Some("end_header") => break,
            Some(other) => return Err(format!("unknown header keyword \"{other}\"")),
        }
    }
    let format = format.ok_or("the header has no format line")?;
    Ok((format, elements, bytes.get(pos..).unwrap_or_default()))
}
