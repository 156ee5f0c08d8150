//! Train once, use everywhere: `ember train` stores what an estimator's setup computes
//! (SPCBPT's κ trees, Q and Γ) so that every task of a split render loads it with
//! `--model` instead of repeating it (docs/distributed.md).
//!
//! The file: a text header, one `key: value` per line after the first line
//! [`HEADER`], ended by an empty line, then the core's model bytes
//! (`ember_core::estimators::spcbpt::model_file`: versioned, checksummed, validated on
//! reading). The header names what the model is valid for: the program build, the scene
//! hash, the estimator and its configuration, the seed and the resolution; a render
//! loading it must match every one, else the file is refused naming the field.

use std::path::Path;

use ember_core::estimators::Renderer;
use ember_core::estimators::spcbpt::Model;
use ember_core::scene::Scene;

use crate::distributed::RenderIdentity;

/// The file's first line.
pub const HEADER: &str = "ember trained model 1";
/// The largest model file read: Γ of 4096² subspaces (134 MB) and the trees, with room.
const MAX_MODEL_BYTES: u64 = 1 << 30;

/// The header's fields for a render, in file order.
fn fields(id: &RenderIdentity, width: u32, height: u32) -> Vec<(&'static str, String)> {
    // The resolution before the scene hash (which covers the camera, so changes with it).
    vec![
        ("program", ember_host::program_version()),
        ("estimator", id.estimator.clone()),
        ("resolution", format!("{width}x{height}")),
        ("seed", id.seed.to_string()),
        ("config", id.config.clone()),
        ("scene_hash", format!("{:016x}", id.scene_hash)),
    ]
}

/// The bytes of a model file for `renderer` (its setup run) and the render it belongs to.
pub fn encode(renderer: &Renderer, id: &RenderIdentity, width: u32, height: u32) -> Result<Vec<u8>, String> {
    let Renderer::Spcbpt(s) = renderer else {
        return Err(format!(
            "{} has no trained state to save: only spcbpt trains a model (where the scene plan renders another estimator, --no-plan keeps spcbpt)",
            id.estimator
        ));
    };
    let model = s.model.as_ref().ok_or("the preprocessing has not run")?;
    let mut out = format!("{HEADER}\n");
    // The scene's name is for people: the same scene may sit at another path on another
    // machine, so only its hash is checked.
    for (k, v) in fields(id, width, height).into_iter().chain([("scene", id.scene.clone())]) {
        out.push_str(&format!("{k}: {}\n", v.replace('\n', " ")));
    }
    // The checksum line covers every header line before it (the model's bytes carry
    // their own checksum).
    crate::distributed::sign_header(&mut out);
    out.push('\n');
    let mut bytes = out.into_bytes();
    bytes.extend_from_slice(&model.encode());
    Ok(bytes)
}

/// Read `path` and check it against the render (`id`, `width`×`height`, `scene`): the
/// model, or an error naming the file and the first field that differs.
pub fn load(path: &Path, id: &RenderIdentity, width: u32, height: u32, scene: &Scene) -> Result<Model, String> {
    let name = path.display();
    let bytes = ember_formats::files::read_bounded(path, MAX_MODEL_BYTES).map_err(|e| format!("--model {name}: {e}"))?;
    let end =
        bytes.windows(2).position(|w| w == b"\n\n").ok_or_else(|| format!("--model {name} is not a model file (no header): write one with `ember train`"))?;
    let header = std::str::from_utf8(&bytes[..end]).map_err(|_| format!("--model {name} is not a model file (its header is not text)"))?;
    let mut lines = header.lines();
    if lines.next() != Some(HEADER) {
        return Err(format!("--model {name} is not a model file of this program (first line is not '{HEADER}')"));
    }
    let stored: Vec<(&str, &str)> = lines.filter_map(|l| l.split_once(": ")).collect();
    let value = |key: &str| stored.iter().find(|(k, _)| *k == key).map(|(_, v)| *v);
    if !crate::distributed::header_is_signed(header) {
        return Err(format!("--model {name}: its header does not match its checksum: the header was edited or the file is damaged"));
    }
    for (key, want) in fields(id, width, height) {
        match value(key) {
            Some(v) if v == want => {}
            // The configuration is a long dump and the hash means nothing to a person:
            // name the field that differs and the scenes.
            Some(v) if key == "config" => {
                let (trained, here) = crate::distributed::first_difference(v, &want);
                return Err(format!("--model {name} was trained with another configuration: {trained}, but this render has {here}"));
            }
            Some(_) if key == "scene_hash" => {
                return Err(format!(
                    "--model {name} was trained on another scene: {} (its content differs from this render's {}); train one for this scene with `ember train`",
                    value("scene").unwrap_or("(unnamed)"),
                    id.scene
                ));
            }
            Some(v) => return Err(format!("--model {name} was trained with {key} {v}, but this render has {want}")),
            None => return Err(format!("--model {name}: its header has no {key}")),
        }
    }
    Model::decode(&bytes[end + 2..], scene).map_err(|e| format!("--model {name}: {e}"))
}
