//! Meshes: each primitive's positions and indices as a triangle list in its node's space,
//! with TEXCOORD_0, TEXCOORD_1 and COLOR_0 where it has them. Triangle strips and fans become
//! lists with glTF's winding; points and lines are skipped.

use super::buffers::{self, Buffers};
use super::{Ctx, LoadError, MAX_COORD};
use crate::scene::Primitive;
use glam::{Vec2, Vec3, Vec4};
use gltf::mesh::{Mode, Semantic};
use std::collections::BTreeSet;

/// Every mesh as a list of triangle primitives; `default_material` stands in where a
/// primitive names none.
pub(super) fn read(
    cx: &mut Ctx,
    doc: &gltf::Document,
    buffers: &Buffers,
    default_material: usize,
) -> Result<Vec<Vec<Primitive>>, LoadError> {
    let mut meshes = Vec::new();
    let mut triangles = 0usize;
    let mut skipped_modes = BTreeSet::new();
    for mesh in doc.meshes() {
        let mut prims = Vec::new();
        for prim in mesh.primitives() {
            if !matches!(
                prim.mode(),
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                skipped_modes.insert(format!("{:?}", prim.mode()));
                continue;
            }
            let p = primitive(cx, &mesh, &prim, buffers, default_material)?;
            triangles += p.indices.len() / 3;
            prims.push(p);
        }
        meshes.push(prims);
    }
    let skipped = skipped_modes.into_iter().collect::<Vec<_>>().join(", ");
    if !skipped.is_empty() {
        if triangles == 0 {
            return Err(cx.err(format!(
                "no triangle primitives: the meshes hold only {skipped} (irad renders triangles)"
            )));
        }
        cx.warn(format!("non-triangle primitives ({skipped}) are ignored"));
    }
    if triangles == 0 {
        return Err(cx.err("no triangles: the file has no mesh to render"));
    }
    Ok(meshes)
}

fn primitive(
    cx: &mut Ctx,
    mesh: &gltf::Mesh,
    prim: &gltf::Primitive,
    buffers: &Buffers,
    default_material: usize,
) -> Result<Primitive, LoadError> {
    warn_ignored(cx, prim);
    let positions = positions(cx, mesh, prim, buffers)?;
    let what = format!("indices of mesh {}", mesh.index());
    let indices: Vec<u32> = match prim.indices() {
        Some(acc) => buffers::indices(cx, buffers, &acc, &what)?,
        None => (0..positions.len() as u32).collect(),
    };
    // Named by place, not value: the value is the file's bytes.
    if let Some(bad) = indices.iter().position(|&i| i as usize >= positions.len()) {
        return Err(cx.err(format!(
            "mesh {} has index number {bad} beyond its {} vertices",
            mesh.index(),
            positions.len()
        )));
    }
    let n = positions.len();
    let uv = [0, 1].map(|set| {
        let acc = prim.get(&Semantic::TexCoords(set))?;
        let what = format!("TEXCOORD_{set} of mesh {}", mesh.index());
        vertex_attribute(cx, buffers, &acc, &what, n, 2)
            .map(|f| f.chunks_exact(2).map(Vec2::from_slice).collect())
    });
    let colors = prim.get(&Semantic::Colors(0)).and_then(|acc| {
        let what = format!("COLOR_0 of mesh {}", mesh.index());
        let w = buffers::width(acc.dimensions());
        if w != 3 && w != 4 {
            cx.warn(format!("{what} is neither VEC3 nor VEC4 and is ignored"));
            return None;
        }
        vertex_attribute(cx, buffers, &acc, &what, n, w).map(|f| {
            f.chunks_exact(w)
                .map(|c| {
                    let a = if w == 4 { c[3] } else { 1.0 };
                    Vec4::new(c[0], c[1], c[2], a).clamp(Vec4::ZERO, Vec4::ONE)
                })
                .collect()
        })
    });
    Ok(Primitive {
        positions,
        indices: triangle_list(prim.mode(), &indices),
        material: prim.material().index().unwrap_or(default_material),
        uv,
        colors,
    })
}

/// A per-vertex attribute of `width` components, one per position, all finite; else a
/// warning saying it is ignored.
fn vertex_attribute(
    cx: &mut Ctx,
    buffers: &Buffers,
    acc: &gltf::Accessor,
    what: &str,
    vertices: usize,
    width: usize,
) -> Option<Vec<f32>> {
    if buffers::width(acc.dimensions()) != width {
        cx.warn(format!("{what} has the wrong type and is ignored"));
        return None;
    }
    let f = match buffers::floats(cx, buffers, acc, what) {
        Ok(f) => f,
        Err(e) => {
            cx.warn(format!(
                "{what} cannot be read and is ignored ({})",
                e.reason
            ));
            return None;
        }
    };
    if f.len() != vertices * width {
        cx.warn(format!(
            "{what} has {} values for {vertices} vertices and is ignored",
            f.len() / width
        ));
        return None;
    }
    if f.iter().any(|x| !x.is_finite()) {
        cx.warn(format!(
            "{what} holds NaN or infinite values and is ignored"
        ));
        return None;
    }
    Some(f)
}

/// One warning per kind of vertex data irad does not use, saying what it changes.
fn warn_ignored(cx: &mut Ctx, prim: &gltf::Primitive) {
    if prim.morph_targets().next().is_some() {
        cx.warn("morph targets are ignored: meshes keep their base shape");
    }
    for (sem, _) in prim.attributes() {
        match sem {
            Semantic::Colors(k) if k > 0 => cx.warn(
                "vertex colours beyond COLOR_0 are ignored",
            ),
            Semantic::Normals => cx.warn(
                "vertex normals (NORMAL) are ignored: each triangle is shaded flat with its geometric normal",
            ),
            _ => {}
        }
    }
}

/// POSITION as finite VEC3s within irad's coordinate limit (any component type, so
/// KHR_mesh_quantization's integer positions read too). A bad vertex is named by index, not
/// value: the values are the file's bytes, which a message must not echo.
fn positions(
    cx: &Ctx,
    mesh: &gltf::Mesh,
    prim: &gltf::Primitive,
    buffers: &Buffers,
) -> Result<Vec<Vec3>, LoadError> {
    let Some(acc) = prim.get(&Semantic::Positions) else {
        return Err(cx.err(format!(
            "mesh {} has a primitive without POSITION",
            mesh.index()
        )));
    };
    if acc.dimensions() != gltf::accessor::Dimensions::Vec3 {
        return Err(cx.err(format!(
            "accessor {} (POSITION of mesh {}) is {:?}, not VEC3",
            acc.index(),
            mesh.index(),
            acc.dimensions()
        )));
    }
    let what = format!("POSITION of mesh {}", mesh.index());
    let flat = buffers::floats(cx, buffers, &acc, &what)?;
    let positions: Vec<Vec3> = flat.chunks_exact(3).map(Vec3::from_slice).collect();
    if let Some(bad) = positions.iter().position(|p| !p.is_finite()) {
        return Err(cx.err(format!(
            "mesh {} ('{}') has a NaN or infinite position at vertex {bad}",
            mesh.index(),
            mesh.name().unwrap_or(""),
        )));
    }
    if let Some(bad) = positions
        .iter()
        .position(|p| p.abs().max_element() > MAX_COORD)
    {
        return Err(cx.err(format!(
            "mesh {} ('{}') has vertex {bad} beyond irad's coordinate limit of {MAX_COORD:e}",
            mesh.index(),
            mesh.name().unwrap_or(""),
        )));
    }
    Ok(positions)
}

/// Indices of a triangle list, strip or fan as a list (glTF 2.0 section 3.7.2.1: strip
/// triangle i is (i, i+1+i%2, i+2-i%2), fan triangle i is (i+1, i+2, 0)); a list's trailing
/// partial triangle is dropped.
fn triangle_list(mode: Mode, idx: &[u32]) -> Vec<u32> {
    let n = idx.len();
    match mode {
        Mode::TriangleStrip => (0..n.saturating_sub(2))
            .flat_map(|i| [idx[i], idx[i + 1 + i % 2], idx[i + 2 - i % 2]])
            .collect(),
        Mode::TriangleFan => (0..n.saturating_sub(2))
            .flat_map(|i| [idx[i + 1], idx[i + 2], idx[0]])
            .collect(),
        _ => idx[..n / 3 * 3].to_vec(),
    }
}
