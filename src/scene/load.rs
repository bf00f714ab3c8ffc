//! glTF 2.0 loading (.gltf with external or embedded buffers, and .glb).
//!
//! What irad uses: triangle meshes, node transforms, baseColorFactor (albedo),
//! emissiveFactor x KHR_materials_emissive_strength (emitted radiance), the first perspective
//! camera, and node animations. Everything else is ignored with one warning per kind.

use super::{anim, Camera, CameraDef, Local, Material, Node, Primitive, Scene};
use glam::{Mat4, Quat, Vec3, Vec4};
use gltf::animation::util::ReadOutputs;
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
    let err = |reason: String| LoadError {
        file: file.to_string(),
        reason,
    };
    let gltf = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| err(format!("not a glTF 2.0 file (.gltf JSON or .glb): {e}")))?;
    let doc = &gltf.document;
    for ext in doc.extensions_required() {
        if !SUPPORTED_EXTENSIONS.contains(&ext) {
            return Err(err(format!(
                "requires the glTF extension {ext}, which irad does not support (it supports {})",
                SUPPORTED_EXTENSIONS.join(", ")
            )));
        }
    }
    let gltf = gltf::Gltf::from_slice(bytes).map_err(|e| err(format!("invalid glTF: {e}")))?;
    let doc = &gltf.document;
    for buf in doc.buffers() {
        if let gltf::buffer::Source::Uri(uri) = buf.source() {
            if !uri.starts_with("data:") {
                let full = base.unwrap_or(Path::new(".")).join(uri);
                if let Err(e) = std::fs::metadata(&full) {
                    return Err(err(format!(
                        "buffer {} refers to '{uri}' ({}), which cannot be read: {e}",
                        buf.index(),
                        full.display()
                    )));
                }
            }
        }
    }
    let buffers =
        gltf::import_buffers(doc, Some(base.unwrap_or(Path::new("."))), gltf.blob.clone())
            .map_err(|e| match e {
                gltf::Error::BufferLength {
                    buffer,
                    expected,
                    actual,
                } => err(format!(
                    "buffer {buffer} is short: it declares {expected} bytes but holds {actual}"
                )),
                gltf::Error::Io(io) => err(format!("a buffer cannot be read: {io}")),
                gltf::Error::MissingBlob => {
                    err("the .glb has no BIN chunk but a buffer refers to it".into())
                }
                other => err(format!("a buffer cannot be loaded: {other}")),
            })?;
    // Bounds of every buffer view and accessor, so that reading can never go past the data.
    for view in doc.views() {
        let len = buffers[view.buffer().index()].len();
        if view.offset() + view.length() > len {
            return Err(err(format!(
                "bufferView {} spans bytes {}..{} of buffer {} which holds {len}",
                view.index(),
                view.offset(),
                view.offset() + view.length(),
                view.buffer().index()
            )));
        }
    }
    for acc in doc.accessors() {
        if acc.sparse().is_some() {
            return Err(err(format!(
                "accessor {} is sparse, which irad does not read",
                acc.index()
            )));
        }
        let Some(view) = acc.view() else { continue };
        let elem = acc.size();
        let stride = view.stride().unwrap_or(elem);
        let need = if acc.count() == 0 {
            0
        } else {
            acc.offset() + stride * (acc.count() - 1) + elem
        };
        if need > view.length() {
            return Err(err(format!(
                "accessor {} needs {need} bytes of bufferView {} which has {}",
                acc.index(),
                view.index(),
                view.length()
            )));
        }
    }

    let mut warnings = BTreeSet::new();
    for ext in doc.extensions_used() {
        if !SUPPORTED_EXTENSIONS.contains(&ext) {
            warnings.insert(format!("extension {ext} is ignored"));
        }
    }
    if doc.textures().next().is_some() {
        warnings.insert("textures are ignored: albedo is baseColorFactor".to_string());
    }
    if doc.skins().next().is_some() {
        warnings.insert("skins are ignored".to_string());
    }

    // Materials; index `len` is the glTF default material.
    let mut materials = Vec::new();
    for m in doc.materials() {
        let pbr = m.pbr_metallic_roughness();
        let bc = Vec4::from(pbr.base_color_factor());
        let mut albedo = bc.truncate();
        if albedo.max_element() > 1.0 || albedo.min_element() < 0.0 {
            warnings.insert("albedo outside [0,1] is clamped".into());
            albedo = albedo.clamp(Vec3::ZERO, Vec3::ONE);
        }
        if pbr.metallic_factor() > 0.0 {
            warnings.insert("metallic-roughness is ignored: every surface is Lambertian".into());
        }
        if pbr.base_color_texture().is_some()
            || m.emissive_texture().is_some()
            || m.normal_texture().is_some()
        {
            warnings.insert("material textures are ignored".into());
        }
        if bc.w < 1.0 || m.alpha_mode() != gltf::material::AlphaMode::Opaque {
            warnings.insert("transparency is ignored: every surface is opaque".into());
        }
        let strength = m.emissive_strength().unwrap_or(1.0);
        let emission = Vec3::from(m.emissive_factor()) * strength;
        if !emission.is_finite() || emission.min_element() < 0.0 {
            return Err(err(format!(
                "material {} has an invalid emission {emission}",
                m.index().unwrap_or(0)
            )));
        }
        materials.push(Material {
            name: m.name().unwrap_or("").to_string(),
            albedo,
            emission,
        });
    }
    let default_material = materials.len();
    materials.push(Material {
        name: "default".into(),
        albedo: Vec3::splat(1.0),
        emission: Vec3::ZERO,
    });

    // Meshes: triangle primitives only.
    let mut meshes = Vec::new();
    let mut triangles = 0usize;
    let mut skipped_modes = BTreeSet::new();
    for mesh in doc.meshes() {
        let mut prims = Vec::new();
        for prim in mesh.primitives() {
            use gltf::mesh::Mode;
            if prim.mode() != Mode::Triangles {
                skipped_modes.insert(format!("{:?}", prim.mode()));
                continue;
            }
            if prim.morph_targets().next().is_some() {
                warnings.insert("morph targets are ignored".into());
            }
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let Some(pos) = reader.read_positions() else {
                return Err(err(format!(
                    "mesh {} has a primitive without POSITION",
                    mesh.index()
                )));
            };
            let positions: Vec<Vec3> = pos.map(Vec3::from).collect();
            if let Some(bad) = positions.iter().position(|p| !p.is_finite()) {
                return Err(err(format!(
                    "mesh {} ('{}') has a NaN or infinite position at vertex {bad}: {}",
                    mesh.index(),
                    mesh.name().unwrap_or(""),
                    positions[bad]
                )));
            }
            let indices: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..positions.len() as u32).collect(),
            };
            if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
                return Err(err(format!(
                    "mesh {} has index {bad} but only {} vertices",
                    mesh.index(),
                    positions.len()
                )));
            }
            let indices = indices[..indices.len() / 3 * 3].to_vec();
            triangles += indices.len() / 3;
            prims.push(Primitive {
                positions,
                indices,
                material: prim.material().index().unwrap_or(default_material),
            });
        }
        meshes.push(prims);
    }
    if !skipped_modes.is_empty() {
        if triangles == 0 {
            return Err(err(format!(
                "no triangle primitives: the meshes hold only {} (irad renders triangles)",
                skipped_modes.into_iter().collect::<Vec<_>>().join(", ")
            )));
        }
        warnings.insert(format!(
            "non-triangle primitives ({}) are ignored",
            skipped_modes.into_iter().collect::<Vec<_>>().join(", ")
        ));
    }
    if triangles == 0 {
        return Err(err("no triangles: the file has no mesh to render".into()));
    }

    // Nodes.
    let mut nodes = Vec::new();
    let mut first_camera = None;
    for n in doc.nodes() {
        let local = match n.transform() {
            gltf::scene::Transform::Matrix { matrix } => {
                let m = Mat4::from_cols_array_2d(&matrix);
                if !m.is_finite() {
                    return Err(err(format!("node {} has a non-finite matrix", n.index())));
                }
                Local::Matrix(m)
            }
            gltf::scene::Transform::Decomposed {
                translation,
                rotation,
                scale,
            } => {
                let (t, r, s) = (
                    Vec3::from(translation),
                    Quat::from_array(rotation),
                    Vec3::from(scale),
                );
                if !(t.is_finite() && r.is_finite() && s.is_finite()) {
                    return Err(err(format!(
                        "node {} has a non-finite transform",
                        n.index()
                    )));
                }
                Local::Trs {
                    translation: t,
                    rotation: r.normalize(),
                    scale: s,
                }
            }
        };
        let camera = match n.camera().as_ref().map(|c| c.projection()) {
            Some(gltf::camera::Projection::Perspective(p)) => Some(CameraDef { yfov: p.yfov() }),
            Some(gltf::camera::Projection::Orthographic(_)) => {
                warnings.insert("orthographic cameras are ignored".into());
                None
            }
            None => None,
        };
        if camera.is_some() && first_camera.is_none() {
            first_camera = Some(n.index());
        }
        nodes.push(Node {
            name: n.name().unwrap_or("").to_string(),
            local,
            children: n.children().map(|c| c.index()).collect(),
            mesh: n.mesh().map(|m| m.index()),
            camera,
        });
    }
    let roots: Vec<usize> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(s) => s.nodes().map(|n| n.index()).collect(),
        None => {
            let mut is_child = vec![false; nodes.len()];
            for n in &nodes {
                for &c in &n.children {
                    is_child[c] = true;
                }
            }
            (0..nodes.len()).filter(|&i| !is_child[i]).collect()
        }
    };
    // Only cameras reachable from the roots count.
    let reachable = {
        let mut seen = vec![false; nodes.len()];
        let mut stack = roots.clone();
        while let Some(n) = stack.pop() {
            if !std::mem::replace(&mut seen[n], true) {
                stack.extend(nodes[n].children.iter());
            }
        }
        seen
    };
    let camera_node = first_camera
        .filter(|&c| reachable[c])
        .or_else(|| (0..nodes.len()).find(|&i| reachable[i] && nodes[i].camera.is_some()));

    // Animations.
    let mut channels = Vec::new();
    for a in doc.animations() {
        for c in a.channels() {
            let node = c.target().node().index();
            let reader = c.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let times: Vec<f32> = match reader.read_inputs() {
                Some(t) => t.collect(),
                None => {
                    return Err(err(format!(
                        "animation {} has a channel without key times",
                        a.index()
                    )))
                }
            };
            if times.is_empty()
                || times.iter().any(|t| !t.is_finite())
                || times.windows(2).any(|w| w[1] < w[0])
            {
                return Err(err(format!(
                    "animation {} has key times that are empty, non-finite or not increasing",
                    a.index()
                )));
            }
            let (property, values): (anim::Property, Vec<Vec4>) = match reader.read_outputs() {
                Some(ReadOutputs::Translations(v)) => (
                    anim::Property::Translation,
                    v.map(|x| Vec3::from(x).extend(0.0)).collect(),
                ),
                Some(ReadOutputs::Scales(v)) => (
                    anim::Property::Scale,
                    v.map(|x| Vec3::from(x).extend(0.0)).collect(),
                ),
                Some(ReadOutputs::Rotations(r)) => (
                    anim::Property::Rotation,
                    r.into_f32().map(Vec4::from).collect(),
                ),
                Some(ReadOutputs::MorphTargetWeights(_)) => {
                    warnings.insert("morph-target weight animations are ignored".into());
                    continue;
                }
                None => {
                    return Err(err(format!(
                        "animation {} has a channel without values",
                        a.index()
                    )))
                }
            };
            let interpolation = match c.sampler().interpolation() {
                gltf::animation::Interpolation::Step => anim::Interpolation::Step,
                gltf::animation::Interpolation::Linear => anim::Interpolation::Linear,
                gltf::animation::Interpolation::CubicSpline => anim::Interpolation::CubicSpline,
            };
            let per_key = if interpolation == anim::Interpolation::CubicSpline {
                3
            } else {
                1
            };
            if values.len() != times.len() * per_key || values.iter().any(|v| !v.is_finite()) {
                return Err(err(format!(
                    "animation {} has {} values for {} keys (needs {} finite values)",
                    a.index(),
                    values.len(),
                    times.len(),
                    times.len() * per_key
                )));
            }
            if let Local::Matrix(m) = nodes[node].local {
                warnings.insert("an animated node had a matrix; it was decomposed into TRS".into());
                let (s, r, t) = m.to_scale_rotation_translation();
                nodes[node].local = Local::Trs {
                    translation: t,
                    rotation: r,
                    scale: s,
                };
            }
            channels.push(anim::Channel {
                node,
                property,
                interpolation,
                times,
                values,
            });
        }
    }

    let mut scene = Scene {
        name: name.to_string(),
        materials: Arc::new(materials),
        meshes,
        nodes,
        roots,
        camera_node,
        default_camera: Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 0.7),
        channels,
        warnings: Vec::new(),
    };
    let frame0 = scene.at(0.0);
    if frame0.tris.is_empty() {
        return Err(err("no triangles in the scene's node tree".into()));
    }
    if scene.camera_node.is_none() {
        let (lo, hi) = frame0.bounds();
        scene.default_camera = Camera::framing(lo, hi);
        warnings.insert(
            "no perspective camera: using a default camera that frames the scene from +Z".into(),
        );
    }
    let lit = (0..=(scene.duration() * 10.0).ceil() as usize)
        .map(|i| i as f32 * 0.1)
        .any(|t| !scene.at(t).emitters.tris.is_empty());
    if !lit {
        return Err(err(
            "no emitter: no triangle has a material with emissiveFactor > 0, so there is nothing to light the scene"
                .into(),
        ));
    }
    scene.warnings = warnings
        .into_iter()
        .map(|w| format!("{file}: {w}"))
        .collect();
    Ok(scene)
}
