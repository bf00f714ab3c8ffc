//! glTF 2.0 loading (.gltf with external or embedded buffers, and .glb), one module per part
//! of glTF it reads: `buffers` (buffers, views, accessors), `material`, `mesh` (primitives),
//! `nodes` (the node tree and cameras) and `animation`.
//!
//! What irad uses: triangle meshes, node transforms, baseColorFactor (albedo),
//! emissiveFactor x KHR_materials_emissive_strength (emitted radiance), the first perspective
//! camera, and node animations. Everything else is ignored with one warning per kind.

mod animation;
mod buffers;
mod material;
mod mesh;
mod nodes;

use super::{Camera, Scene};
use glam::Vec3;
use std::collections::BTreeSet;
use std::path::Path;
use std::sync::Arc;

/// A scene file irad cannot use: the file and what is wrong with it.
#[derive(Debug, thiserror::Error)]
#[error("{file}: {reason}")]
pub struct LoadError {
    pub file: String,
    pub reason: String,
}

/// Extensions irad understands; a file that requires any other is refused.
const SUPPORTED_EXTENSIONS: &[&str] = &["KHR_materials_emissive_strength"];

/// What every part of the loader shares: the file's name for messages, and the warnings.
struct Ctx<'a> {
    file: &'a str,
    warnings: BTreeSet<String>,
}

impl Ctx<'_> {
    fn err(&self, reason: impl Into<String>) -> LoadError {
        LoadError {
            file: self.file.to_string(),
            reason: reason.into(),
        }
    }

    fn warn(&mut self, w: impl Into<String>) {
        self.warnings.insert(w.into());
    }
}

/// Loads a scene from a file path.
pub fn load_path(path: &Path) -> Result<Scene, LoadError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| LoadError {
        file: file.clone(),
        reason: format!("cannot read the file: {e}"),
    })?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| file.clone());
    load_slice(&bytes, &file, &name, path.parent())
}

/// Loads a scene from bytes; `file` names it in messages, `base` resolves external buffers.
pub fn load_slice(
    bytes: &[u8],
    file: &str,
    name: &str,
    base: Option<&Path>,
) -> Result<Scene, LoadError> {
    let mut cx = Ctx {
        file,
        warnings: BTreeSet::new(),
    };
    let gltf = parse(&cx, bytes)?;
    let doc = &gltf.document;
    let buffers = buffers::load(&cx, doc, base, gltf.blob.clone())?;
    warn_unused(&mut cx, doc);
    let materials = material::read(&mut cx, doc)?;
    let meshes = mesh::read(&mut cx, doc, &buffers, materials.len() - 1)?;
    let mut graph = nodes::read(&mut cx, doc)?;
    let channels = animation::read(&mut cx, doc, &buffers, &mut graph.nodes)?;
    let scene = Scene {
        name: name.to_string(),
        materials: Arc::new(materials),
        meshes,
        nodes: graph.nodes,
        roots: graph.roots,
        camera_node: graph.camera_node,
        default_camera: Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 0.7),
        channels,
        warnings: Vec::new(),
    };
    finish(cx, scene)
}

/// Parses the JSON (or .glb container) and refuses extensions irad does not support.
fn parse(cx: &Ctx, bytes: &[u8]) -> Result<gltf::Gltf, LoadError> {
    let gltf = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| cx.err(format!("not a glTF 2.0 file (.gltf JSON or .glb): {e}")))?;
    for ext in gltf.document.extensions_required() {
        if !SUPPORTED_EXTENSIONS.contains(&ext) {
            return Err(cx.err(format!(
                "requires the glTF extension {ext}, which irad does not support (it supports {})",
                SUPPORTED_EXTENSIONS.join(", ")
            )));
        }
    }
    gltf::Gltf::from_slice(bytes).map_err(|e| cx.err(format!("invalid glTF: {e}")))
}

/// One warning per kind of thing in the file that irad ignores as a whole.
fn warn_unused(cx: &mut Ctx, doc: &gltf::Document) {
    for ext in doc.extensions_used() {
        if !SUPPORTED_EXTENSIONS.contains(&ext) {
            cx.warn(format!("extension {ext} is ignored"));
        }
    }
    if doc.textures().next().is_some() {
        cx.warn("textures are ignored: albedo is baseColorFactor");
    }
    if doc.skins().next().is_some() {
        cx.warn("skins are ignored");
    }
}

/// Checks the evaluated scene (triangles, a camera, an emitter) and attaches the warnings.
fn finish(mut cx: Ctx, mut scene: Scene) -> Result<Scene, LoadError> {
    let frame0 = scene.at(0.0);
    if frame0.tris.is_empty() {
        return Err(cx.err("no triangles in the scene's node tree"));
    }
    if scene.camera_node.is_none() {
        let (lo, hi) = frame0.bounds();
        scene.default_camera = Camera::framing(lo, hi);
        cx.warn("no perspective camera: using a default camera that frames the scene from +Z");
    }
    let lit = (0..=(scene.duration() * 10.0).ceil() as usize)
        .map(|i| i as f32 * 0.1)
        .any(|t| !scene.at(t).emitters.tris.is_empty());
    if !lit {
        return Err(cx.err(
            "no emitter: no triangle has a material with emissiveFactor > 0, so there is nothing to light the scene",
        ));
    }
    let file = cx.file;
    scene.warnings = cx
        .warnings
        .into_iter()
        .map(|w| format!("{file}: {w}"))
        .collect();
    Ok(scene)
}
