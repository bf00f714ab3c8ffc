//! Materials: albedo from baseColorFactor, emitted radiance from emissiveFactor x
//! KHR_materials_emissive_strength; the rest of glTF's PBR model is ignored with a warning.

use super::{Ctx, LoadError};
use crate::scene::Material;
use glam::{Vec3, Vec4};

/// The largest emitted radiance irad accepts, per channel.
const MAX_RADIANCE: f32 = 1e8;

/// Every material of the file, then the glTF default material (white, not emitting) last.
pub(super) fn read(cx: &mut Ctx, doc: &gltf::Document) -> Result<Vec<Material>, LoadError> {
    let mut materials = Vec::new();
    for m in doc.materials() {
        materials.push(one(cx, &m)?);
    }
    materials.push(Material {
        name: "default".into(),
        albedo: Vec3::splat(1.0),
        emission: Vec3::ZERO,
        double_sided: false,
    });
    Ok(materials)
}

fn one(cx: &mut Ctx, m: &gltf::Material) -> Result<Material, LoadError> {
    let pbr = m.pbr_metallic_roughness();
    let bc = Vec4::from(pbr.base_color_factor());
    let mut albedo = bc.truncate();
    if albedo.max_element() > 1.0 || albedo.min_element() < 0.0 {
        cx.warn("albedo outside [0,1] is clamped");
        albedo = albedo.clamp(Vec3::ZERO, Vec3::ONE);
    }
    if pbr.metallic_factor() > 0.0 {
        cx.warn("metallic-roughness is ignored: every surface is Lambertian");
    }
    if pbr.base_color_texture().is_some()
        || m.emissive_texture().is_some()
        || m.normal_texture().is_some()
    {
        cx.warn("material textures are ignored");
    }
    if bc.w < 1.0 || m.alpha_mode() != gltf::material::AlphaMode::Opaque {
        cx.warn("transparency is ignored: every surface is opaque");
    }
    let strength = m.emissive_strength().unwrap_or(1.0);
    let emission = Vec3::from(m.emissive_factor()) * strength;
    if !emission.is_finite() || emission.min_element() < 0.0 {
        return Err(cx.err(format!(
            "material {} has an invalid emission {emission}",
            m.index().unwrap_or(0)
        )));
    }
    if emission.max_element() > MAX_RADIANCE {
        return Err(cx.err(format!(
            "material {} ('{}') emits {emission}, above irad's limit of {MAX_RADIANCE:e} (light is summed in 32-bit floats; the sun's radiance is about 2e7)",
            m.index().unwrap_or(0),
            m.name().unwrap_or("")
        )));
    }
    Ok(Material {
        name: m.name().unwrap_or("").to_string(),
        albedo,
        emission,
        double_sided: m.double_sided(),
    })
}
