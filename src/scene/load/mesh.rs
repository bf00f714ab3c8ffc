//! Meshes: each primitive's positions and indices as a triangle list in its node's space.

use super::buffers::Buffers;
use super::{Ctx, LoadError};
use crate::scene::Primitive;
use glam::Vec3;
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
            if prim.mode() != gltf::mesh::Mode::Triangles {
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
    if prim.morph_targets().next().is_some() {
        cx.warn("morph targets are ignored");
    }
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let Some(pos) = reader.read_positions() else {
        return Err(cx.err(format!(
            "mesh {} has a primitive without POSITION",
            mesh.index()
        )));
    };
    let positions: Vec<Vec3> = pos.map(Vec3::from).collect();
    if let Some(bad) = positions.iter().position(|p| !p.is_finite()) {
        return Err(cx.err(format!(
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
        return Err(cx.err(format!(
            "mesh {} has index {bad} but only {} vertices",
            mesh.index(),
            positions.len()
        )));
    }
    let indices = indices[..indices.len() / 3 * 3].to_vec();
    Ok(Primitive {
        positions,
        indices,
        material: prim.material().index().unwrap_or(default_material),
    })
}
