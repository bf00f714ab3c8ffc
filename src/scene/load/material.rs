//! Materials: albedo from baseColorFactor and baseColorTexture, emitted radiance from
//! emissiveFactor x KHR_materials_emissive_strength and emissiveTexture (each texture with its
//! UV set and KHR_texture_transform), alpha MASK cut-outs; the rest of glTF's PBR model is
//! ignored with a warning.

use super::{Ctx, LoadError};
use crate::scene::{Material, TexRef};
use glam::{Mat3, Vec3, Vec4};

/// The largest emitted radiance irad accepts, per channel.
const MAX_RADIANCE: f32 = 1e8;

/// Every material of the file, then the glTF default material (white, not emitting) last.
/// `textures[i]`: where glTF texture i is in the scene's textures (None: its image could not
/// be read).
pub(super) fn read(
    cx: &mut Ctx,
    doc: &gltf::Document,
    textures: &[Option<usize>],
) -> Result<Vec<Material>, LoadError> {
    let mut materials = Vec::new();
    for m in doc.materials() {
        materials.push(one(cx, &m, textures)?);
    }
    materials.push(Material {
        name: "default".into(),
        ..Material::default()
    });
    Ok(materials)
}

/// A texture reference, if its texture could be read.
fn tex_ref(cx: &mut Ctx, info: &gltf::texture::Info, textures: &[Option<usize>]) -> Option<TexRef> {
    let texture = (*textures.get(info.texture().index())?)?;
    let (mut texcoord, mut transform) = (info.tex_coord(), Mat3::IDENTITY);
    if let Some(t) = info.texture_transform() {
        transform = TexRef::transform(t.offset(), t.rotation(), t.scale());
        texcoord = t.tex_coord().unwrap_or(texcoord);
        if !transform.is_finite() {
            cx.warn("a KHR_texture_transform that is not finite is ignored");
            transform = Mat3::IDENTITY;
        }
    }
    if texcoord > 1 {
        cx.warn("texture coordinate sets beyond TEXCOORD_1 are read as TEXCOORD_0");
        texcoord = 0;
    }
    Some(TexRef {
        texture,
        texcoord,
        transform,
    })
}

fn one(
    cx: &mut Ctx,
    m: &gltf::Material,
    textures: &[Option<usize>],
) -> Result<Material, LoadError> {
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
    if m.normal_texture().is_some()
        || m.occlusion_texture().is_some()
        || pbr.metallic_roughness_texture().is_some()
    {
        cx.warn("normal, occlusion and metallic-roughness textures are ignored");
    }
    let base_color_texture = pbr
        .base_color_texture()
        .and_then(|t| tex_ref(cx, &t, textures));
    let emissive_texture = m.emissive_texture().and_then(|t| tex_ref(cx, &t, textures));
    let alpha_cutoff = match m.alpha_mode() {
        gltf::material::AlphaMode::Mask => {
            let c = m.alpha_cutoff().unwrap_or(0.5);
            if !c.is_finite() {
                return Err(cx.err(format!(
                    "material {} has an alphaCutoff that is not a number",
                    m.index().unwrap_or(0)
                )));
            }
            Some(c)
        }
        gltf::material::AlphaMode::Blend => {
            cx.warn("alpha BLEND is ignored: blended surfaces are opaque");
            None
        }
        gltf::material::AlphaMode::Opaque => None,
    };
    let strength = m.emissive_strength().unwrap_or(1.0);
    let emission = Vec3::from(m.emissive_factor()) * strength;
    // Meant to emit (an emissive texture, factor or strength) but emitting nothing.
    let factor = Vec3::from(m.emissive_factor());
    let meant = m.emissive_texture().is_some()
        || factor.max_element() > 0.0
        || m.emissive_strength().is_some_and(|s| s > 0.0);
    if meant && emission.max_element() <= 0.0 {
        cx.warn(format!(
            "material {} ('{}') emits nothing (emissiveFactor {factor} x emissive strength {strength}{}): it lights nothing",
            m.index().unwrap_or(0),
            m.name().unwrap_or(""),
            if m.emissive_texture().is_some() { " x its emissiveTexture" } else { "" }
        ));
    }
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
        base_color_texture,
        emissive_texture,
        alpha: bc.w.clamp(0.0, 1.0),
        alpha_cutoff,
    })
}
