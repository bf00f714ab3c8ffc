//! glTF 2.0 loading (.gltf with external or embedded buffers, and .glb), one module per part
//! of glTF it reads: `buffers` (buffers, views, accessors), `material`, `mesh` (primitives),
//! `nodes` (the node tree, cameras and EXT_mesh_gpu_instancing), `lights`
//! (KHR_lights_punctual) and `animation`.
//!
//! What irad uses: triangle meshes, node transforms, baseColorFactor x baseColorTexture x
//! COLOR_0 (albedo), emissiveFactor x KHR_materials_emissive_strength x emissiveTexture
//! (emitted radiance), alpha MASK, KHR_texture_transform, KHR_lights_punctual lights,
//! EXT_mesh_gpu_instancing, the
//! first perspective camera, and node animations. Everything else is ignored with one
//! warning per kind.

mod animation;
mod buffers;
mod camera;
pub mod files;
mod lights;
mod material;
mod mesh;
mod nodes;
mod textures;

pub use camera::FOV_RANGE;
pub use files::LoadOptions;

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
const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_materials_emissive_strength",
    "KHR_mesh_quantization",
    "KHR_lights_punctual",
    "KHR_texture_transform",
    "EXT_mesh_gpu_instancing",
];

pub use crate::scene::MAX_COORD;

/// The most triangles a scene may instance (each costs about 100 bytes per frame).
pub const MAX_TRIANGLES: usize = 1 << 24;

/// The most times [`finish`] evaluates an animation at to check it.
const CHECK_SAMPLES: usize = 64;

/// What every part of the loader shares: the file's name for messages, the options, and the
/// warnings.
struct Ctx<'a> {
    file: &'a str,
    options: LoadOptions,
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

/// The largest environment map file irad reads.
pub const MAX_ENVIRONMENT_BYTES: u64 = 1 << 30;

/// Reads an equirectangular environment map (.hdr or .exr) from `path`, wherever it is (the
/// user named it); the error names the file and says what is wrong with it.
pub fn read_environment(path: &Path) -> Result<super::Environment, String> {
    let name = path.display().to_string();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if ext != "hdr" && ext != "exr" {
        return Err(format!(
            "{name} is not a .hdr or .exr file (an equirectangular radiance map)"
        ));
    }
    let bytes =
        files::read_regular(path, MAX_ENVIRONMENT_BYTES + 1).map_err(|e| format!("{name} {e}"))?;
    if bytes.len() as u64 > MAX_ENVIRONMENT_BYTES {
        return Err(format!(
            "{name} is larger than {} GiB, irad's limit for an environment map",
            MAX_ENVIRONMENT_BYTES >> 30
        ));
    }
    super::Environment::decode(&name, &ext, &bytes)
}

/// Loads a scene from a file path with the default options (nothing read from outside the
/// file's folder).
pub fn load_path(path: &Path) -> Result<Scene, LoadError> {
    load_path_with(path, &LoadOptions::default())
}

/// Loads a scene from a file path.
pub fn load_path_with(path: &Path, options: &LoadOptions) -> Result<Scene, LoadError> {
    let file = path.display().to_string();
    let bytes = files::read_scene(path).map_err(|e| LoadError {
        file: file.clone(),
        reason: format!("the scene file {e}"),
    })?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| file.clone());
    load_slice_with(&bytes, &file, &name, path.parent(), options)
}

/// Loads a scene from bytes with the default options; `file` names it in messages, `base`
/// resolves external buffers and images (None: the current folder).
pub fn load_slice(
    bytes: &[u8],
    file: &str,
    name: &str,
    base: Option<&Path>,
) -> Result<Scene, LoadError> {
    load_slice_with(bytes, file, name, base, &LoadOptions::default())
}

/// Loads a scene from bytes (see [`load_slice`]).
pub fn load_slice_with(
    bytes: &[u8],
    file: &str,
    name: &str,
    base: Option<&Path>,
    options: &LoadOptions,
) -> Result<Scene, LoadError> {
    let mut cx = Ctx {
        file,
        options: *options,
        warnings: BTreeSet::new(),
    };
    let gltf = parse(&cx, bytes)?;
    let doc = &gltf.document;
    let buffers = buffers::load(&cx, doc, base, gltf.blob.clone())?;
    warn_unused(&mut cx, doc);
    let read = textures::read(&mut cx, doc, &buffers, base)?;
    let mut index = Vec::with_capacity(read.len());
    let mut textures = Vec::new();
    for t in read {
        index.push(t.map(|t| {
            textures.push(t);
            textures.len() - 1
        }));
    }
    let materials = material::read(&mut cx, doc, &index)?;
    let meshes = mesh::read(&mut cx, doc, &buffers, materials.len() - 1)?;
    let lights = lights::read(&mut cx, doc)?;
    let mut graph = nodes::read(&mut cx, doc, lights.len())?;
    nodes::instancing(&cx, doc, &buffers, &mut graph)?;
    let channels = animation::read(&mut cx, doc, &buffers, &mut graph.nodes)?;
    let closed = meshes
        .iter()
        .map(|m| super::culling::is_closed(m, &materials))
        .collect();
    let scene = Scene {
        name: name.to_string(),
        materials: Arc::new(materials),
        meshes,
        closed,
        nodes: graph.nodes,
        roots: graph.roots,
        lights,
        camera_node: graph.camera_node,
        default_camera: Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 0.7),
        channels,
        textures: Arc::new(textures),
        warnings: Vec::new(),
        shift: Vec3::ZERO,
        environment: None,
        unlit: None,
        emission_means: Default::default(),
    };
    finish(cx, scene)
}

/// Parses the JSON (or .glb container) and refuses extensions irad does not support.
fn parse(cx: &Ctx, bytes: &[u8]) -> Result<gltf::Gltf, LoadError> {
    check_glb(cx, bytes)?;
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
    // The gltf crate's validation refuses required extensions it does not know itself.
    let mut root = gltf.document.into_json();
    root.extensions_required
        .retain(|e| !SUPPORTED_EXTENSIONS.contains(&e.as_str()));
    // Its validation indexes POSITION accessors before checking the index (and panics).
    for (m, mesh) in root.meshes.iter().enumerate() {
        let attrs = mesh.primitives.iter().flat_map(|p| p.attributes.values());
        if let Some(a) = attrs
            .map(|a| a.value())
            .find(|&a| a >= root.accessors.len())
        {
            return Err(cx.err(format!(
                "invalid glTF: mesh {m} refers to accessor {a}, but there are {}",
                root.accessors.len()
            )));
        }
    }
    // Nor does it check animation targets, which the gltf crate unwraps.
    for (i, a) in root.animations.iter().enumerate() {
        for c in &a.channels {
            let valid = matches!(c.target.path, gltf::json::validation::Checked::Valid(_));
            if !valid || c.target.node.value() >= root.nodes.len() {
                return Err(cx.err(format!(
                    "invalid glTF: animation {i} targets node {} of {} or an unknown property",
                    c.target.node.value(),
                    root.nodes.len()
                )));
            }
        }
    }
    let document =
        gltf::Document::from_json(root).map_err(|e| cx.err(format!("invalid glTF: {e}")))?;
    Ok(gltf::Gltf {
        document,
        blob: gltf.blob,
    })
}

/// One warning per kind of thing in the file that irad ignores as a whole.
fn warn_unused(cx: &mut Ctx, doc: &gltf::Document) {
    for ext in doc.extensions_used() {
        if !SUPPORTED_EXTENSIONS.contains(&ext) {
            cx.warn(format!("extension {ext} is ignored"));
        }
    }
    if doc.skins().next().is_some() {
        cx.warn("skins are ignored");
    }
}

/// A .glb's header and chunk lengths fit in the file: a cut-off download says "truncated".
fn check_glb(cx: &Ctx, bytes: &[u8]) -> Result<(), LoadError> {
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    let word = |at: usize| {
        let b = bytes.get(at..at.checked_add(4)?)?;
        Some(u32::from_le_bytes(<[u8; 4]>::try_from(b).ok()?) as usize)
    };
    let truncated = |what: String| {
        cx.err(format!(
            "not a glTF 2.0 file: the .glb is truncated: {what}, but the file holds {} bytes",
            bytes.len()
        ))
    };
    let Some(total) = word(8) else {
        return Err(truncated("its header needs 12 bytes".into()));
    };
    if total > bytes.len() {
        return Err(truncated(format!("its header says {total} bytes")));
    }
    let mut at = 12;
    while at < total {
        let Some(len) = word(at).filter(|_| at + 8 <= total) else {
            return Err(truncated(format!(
                "a chunk header at byte {at} is cut short"
            )));
        };
        if len > total - at - 8 {
            return Err(truncated(format!(
                "the chunk at byte {at} declares {len} bytes and only {} follow",
                total - at - 8
            )));
        }
        at += 8 + len;
    }
    Ok(())
}

/// Checks the evaluated scene (size, coordinates, camera, power, an emitter), moves a scene
/// far from the origin back to it, and attaches the warnings.
fn finish(mut cx: Ctx, mut scene: Scene) -> Result<Scene, LoadError> {
    check_size(&cx, &scene)?;
    let frame0 = scene.at(0.0);
    if frame0.tris.is_empty() {
        return Err(cx.err("no triangles in the scene's node tree"));
    }
    recenter(&mut cx, &mut scene, frame0.bounds());
    check_precision(&cx, &scene)?;
    let frame = scene.at(0.0);
    let (lo, hi) = frame.bounds();
    scene.default_camera = Camera::framing(lo, hi);
    dark_textures(&mut cx, &frame);
    if let Some(why) = check_times(&cx, &scene)? {
        // Lit by the default sky, as every viewer lights such a model (`--environment none`
        // refuses it instead).
        scene.environment = Some(Arc::new(crate::scene::Environment::sky()));
        scene.unlit = Some(format!("{}: {why}", cx.file));
    }
    if scene.camera_node.is_none() {
        scene.default_camera = crate::scene::framing::lit_camera(&scene.at(0.0));
        cx.warn("no perspective camera: using one that frames what the lights light");
    }
    let file = cx.file;
    scene.warnings = cx
        .warnings
        .into_iter()
        .map(|w| format!("{file}: {w}"))
        .collect();
    Ok(scene)
}

/// At most [`MAX_TRIANGLES`] triangles under the roots (the node tree is checked already, so
/// each node is counted once).
fn check_size(cx: &Ctx, scene: &Scene) -> Result<(), LoadError> {
    let mut count = 0usize;
    let mut stack = scene.roots.clone();
    while let Some(n) = stack.pop() {
        let node = &scene.nodes[n];
        if let Some(m) = node.mesh {
            count += scene.meshes[m]
                .iter()
                .map(|p| p.indices.len() / 3)
                .sum::<usize>();
        }
        if count > MAX_TRIANGLES {
            return Err(cx.err(format!(
                "the scene instances more than {MAX_TRIANGLES} triangles, irad's limit"
            )));
        }
        stack.extend(&node.children);
    }
    Ok(())
}

/// A scene whose centre lies more than [`RECENTER`] times its size from the origin is moved
/// to the origin: 32-bit coordinates there are coarse for its detail (rays would leak), and
/// its rays would leave surfaces from farther off them than a scene's at the origin
/// (`trace::POINT_ULPS`).
fn recenter(cx: &mut Ctx, scene: &mut Scene, (lo, hi): (Vec3, Vec3)) {
    let center = (lo + hi) * 0.5;
    let size = (hi - lo).max_element().max(1e-6);
    if center.abs().max_element() > RECENTER * size {
        scene.shift = -center;
        cx.warn(format!(
            "the scene lies {:.3e} units from the origin, {:.0} times its size: it is moved to the origin (by {}) for precision",
            center.length(),
            center.length() / size,
            -center
        ));
    }
}

/// How many times its size from the origin a scene's centre may lie before [`recenter`] moves
/// it there: 15, within which the ray tracer's offsets are the scene's size's alone
/// (`trace::POINT_ULPS`; 100 before stop 52).
pub const RECENTER: f32 = 15.0;

/// The most a mesh's coordinates may be rounded, as a share of its median edge (32-bit floats
/// are up to `|x| * 2^-23` apart near `x`).
const MAX_ROUNDING: f32 = 0.01;

/// The distance from `x >= 0` to the next 32-bit float.
fn spacing(x: f32) -> f32 {
    f32::from_bits(x.to_bits() + 1) - x
}

/// How coarsely points as far as `max_abs` from the origin are rounded, over the median length
/// of the triangles' edges (`tris` as corner positions).
fn rounding(points: impl Iterator<Item = [Vec3; 3]>) -> Option<(f32, f32, f32)> {
    let mut edges = Vec::new();
    let mut max_abs = 0.0f32;
    for [a, b, c] in points {
        max_abs = max_abs.max(a.abs().max(b.abs()).max(c.abs()).max_element());
        edges.extend([(b - a).length(), (c - b).length(), (a - c).length()]);
    }
    if edges.is_empty() || !max_abs.is_finite() {
        return None;
    }
    let mid = edges.len() / 2;
    let median = *edges.select_nth_unstable_by(mid, f32::total_cmp).1;
    // Most edges of no length: nothing to measure the rounding against.
    if median <= 0.0 {
        return None;
    }
    Some((spacing(max_abs) / median, max_abs, median))
}

/// Each mesh's coordinates (as the file stores them) and each placed mesh's (as irad renders
/// them, after [`recenter`]) resolve its shape: rounded by at most [`MAX_ROUNDING`] of its
/// median edge. Past that (a mesh whose vertices themselves lie far from its origin, a small
/// object far from a large scene's centre) the shape is lost to 32-bit floats: an error, not a
/// black or broken frame.
fn check_precision(cx: &Ctx, scene: &Scene) -> Result<(), LoadError> {
    fn tris(p: &crate::scene::Primitive, m: glam::Mat4) -> impl Iterator<Item = [Vec3; 3]> + '_ {
        p.indices.chunks_exact(3).filter_map(move |t| {
            let v = |i: u32| p.positions.get(i as usize).map(|&x| m.transform_point3(x));
            Some([v(t[0])?, v(t[1])?, v(t[2])?])
        })
    }
    let too_coarse = |what: String, (share, max_abs, median): (f32, f32, f32)| {
        cx.err(format!(
            "{what} lies up to {max_abs:.3e} from the origin, where 32-bit floats are {} apart: {:.1}% of its median edge ({median:.3e}), too coarse for its shape; place it by its node's translation (in the file, the vertices near the mesh's own origin) or move the scene nearer the origin",
            spacing(max_abs),
            100.0 * share
        ))
    };
    let mut used = vec![false; scene.meshes.len()];
    let world = scene.world_matrices(0.0);
    let mut stack = scene.roots.clone();
    while let Some(n) = stack.pop() {
        let node = &scene.nodes[n];
        stack.extend(&node.children);
        let Some(m) = node.mesh else { continue };
        let prims = &scene.meshes[m];
        if !used[m] {
            used[m] = true;
            let local = prims.iter().flat_map(|p| tris(p, glam::Mat4::IDENTITY));
            if let Some(r) = rounding(local).filter(|r| r.0 > MAX_ROUNDING) {
                return Err(too_coarse(
                    format!("mesh {m}'s geometry, as the file stores it,"),
                    r,
                ));
            }
        }
        let placed = prims.iter().flat_map(|p| tris(p, world[n]));
        if let Some(r) = rounding(placed).filter(|r| r.0 > MAX_ROUNDING) {
            return Err(too_coarse(
                format!("node {n} ('{}'), placed in the scene,", node.name),
                r,
            ));
        }
    }
    Ok(())
}

/// A material whose emission factor is above zero but whose emissive texture is black
/// wherever its triangles are (its power at t = 0 is zero): a warning naming it.
fn dark_textures(cx: &mut Ctx, frame: &crate::scene::Frame) {
    let mut power = vec![0.0f32; frame.materials.len()];
    let mut used = vec![false; frame.materials.len()];
    for (t, &m) in frame.tri_material.iter().enumerate() {
        used[m as usize] |= frame.areas[t] > 0.0;
    }
    for (&t, &p) in frame.emitters.tris.iter().zip(&frame.emitters.power) {
        power[frame.tri_material[t as usize] as usize] += p.max_element();
    }
    for (i, m) in frame.materials.iter().enumerate() {
        if m.emissive_texture.is_some()
            && m.emission.max_element() > 0.0
            && used[i]
            && power[i] <= 0.0
        {
            cx.warn(format!(
                "material {i} ('{}') emits nothing: its emissiveTexture is black wherever it is used (emissiveFactor x strength {}): it lights nothing",
                m.name, m.emission
            ));
        }
    }
}

/// At times spread over the animation: coordinates within [`MAX_COORD`], a usable camera,
/// finite emitted power. When at none of them anything emits: Some(why).
fn check_times(cx: &Ctx, scene: &Scene) -> Result<Option<String>, LoadError> {
    let d = scene.duration();
    let n = ((d * 10.0).ceil() as usize).min(CHECK_SAMPLES);
    let mut lit = false;
    for i in 0..=n {
        let t = if n == 0 { 0.0 } else { d * i as f32 / n as f32 };
        let f = scene.at(t);
        if let Some(p) = f
            .tris
            .iter()
            .flatten()
            .find(|p| p.abs().max_element() > MAX_COORD)
        {
            return Err(cx.err(format!(
                "at t = {t} s a vertex lies at {p}, beyond irad's coordinate limit of {MAX_COORD:e}"
            )));
        }
        if let Some(l) = f.emitters.lights.iter().find(|l| {
            l.kind != crate::scene::LightKind::Directional
                && l.position.abs().max_element() > MAX_COORD
        }) {
            return Err(cx.err(format!(
                "at t = {t} s KHR_lights_punctual light {} ('{}') lies at {}, beyond irad's coordinate limit of {MAX_COORD:e}",
                l.light, scene.lights[l.light].name, l.position
            )));
        }
        let camera = scene.file_camera(t);
        if let Some(n) = scene
            .camera_node
            .filter(|_| !camera.is_some_and(|c| c.is_valid()))
        {
            return Err(cx.err(format!(
                "at t = {t} s the camera's node {n} ('{}') has no usable view: its transform is scaled to zero or degenerate",
                scene.nodes[n].name
            )));
        }
        for (what, p) in [
            ("emitters'", f.emitters.total_power),
            ("punctual lights'", f.emitters.light_power),
        ] {
            let power = crate::math::luminance(p);
            if !(power.is_finite() && power < 1e30) {
                return Err(cx.err(format!(
                    "at t = {t} s the {what} total power is {p}, too large for 32-bit floats"
                )));
            }
        }
        lit |= !f.emitters.is_empty();
    }
    if !lit {
        let lights = match scene.lights.len() {
            0 => String::new(),
            n => format!(
                " (its {n} KHR_lights_punctual lights are on no node under the scene's roots, or have no intensity)"
            ),
        };
        // The emitters without power, named.
        let dark: Vec<&str> = cx
            .warnings
            .iter()
            .filter(|w| w.contains("emits nothing"))
            .map(String::as_str)
            .collect();
        let dark = if dark.is_empty() {
            String::new()
        } else {
            format!("; {}", dark.join("; "))
        };
        return Ok(Some(format!(
            "no emitter: no triangle has a material with emissiveFactor > 0 and no punctual light shines, so there is nothing to light the scene{lights}{dark}"
        )));
    }
    Ok(None)
}
