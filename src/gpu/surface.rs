//! Surface pass (`shaders/surface.wgsl`): each sample's albedo and emitted radiance where the
//! scene has textures or vertex colours: barycentrics from the G-buffer's position, the
//! corners' UVs and colours, and the material's textures sampled by the rule of
//! `scene::texture` (its CPU twin is `Frame::base_color_at` and `Frame::emission_at`). The
//! passes that apply albedo or emission (`direct`, `gather`, `interleave`, `compose`) read
//! it when `FrameConstants::textured` is set, else the triangle's factors. Scenes without textures or
//! colours skip it.

use super::bindings::{bytes, gpu_struct, params, read, read_write, texture, Elem, Group, Pass};
use super::common::{FrameConstants, Surface, Tri};
use super::{Gpu, PixelPass};
use crate::scene::{Frame, TexRef};
use anyhow::{bail, Result};
use bytemuck::Zeroable;
use glam::Vec2;

gpu_struct! {
    /// A triangle's corners: both UV sets (set 0 in xy, set 1 in zw) and COLOR_0, and its
    /// material index (x of `mat`).
    pub(crate) struct TriAttr {
        pub uv0: [f32; 4],
        pub uv1: [f32; 4],
        pub uv2: [f32; 4],
        pub c0: [f32; 4],
        pub c1: [f32; 4],
        pub c2: [f32; 4],
        pub mat: [u32; 4],
    }
}

gpu_struct! {
    /// A material's textures: (texture index + 1 or 0, UV set) and the two rows of its UV
    /// transform, for the base colour and the emission. Its factors are in `Tri`; its alpha
    /// and its MASK cutoff (negative: none) are the bits of `base_tex.z` and `base_tex.w`.
    pub(crate) struct SurfaceMaterial {
        pub base_tex: [u32; 4],
        pub base_r0: [f32; 4],
        pub base_r1: [f32; 4],
        pub emis_tex: [u32; 4],
        pub emis_r0: [f32; 4],
        pub emis_r1: [f32; 4],
    }
}

gpu_struct! {
    /// A texture in the texel buffer: first texel, size, and `Texture::flags`.
    pub(crate) struct TexInfo {
        pub offset: u32,
        pub width: u32,
        pub height: u32,
        pub flags: u32,
    }
}

pub(crate) const PASS: Pass = Pass {
    name: "surface",
    wgsl: concat!(
        include_str!("../../shaders/texture.wgsl"),
        include_str!("../../shaders/surface.wgsl")
    ),
    groups: &[Group {
        stages: wgpu::ShaderStages::COMPUTE,
        bindings: &[
            params("P", &FrameConstants::LAYOUT),
            read("tris", Elem::Struct(&Tri::LAYOUT)),
            texture("gbuf", wgpu::TextureViewDimension::D2),
            read("attrs", Elem::Struct(&TriAttr::LAYOUT)),
            read("materials", Elem::Struct(&SurfaceMaterial::LAYOUT)),
            read("textures", Elem::Struct(&TexInfo::LAYOUT)),
            read("texels", Elem::Plain(4)),
            read_write("surface", Elem::Struct(&Surface::LAYOUT)),
        ],
    }],
};

gpu_struct! {
    /// Whether any material has an alpha MASK (the G-buffer and shadow passes then test
    /// every fragment with `cut_away`). A storage buffer, not a uniform: lavapipe inlines a
    /// uniform that a branch reads and recompiled the pipelines as the draws went, which
    /// grew memory by 0.9 GiB over 500 frames.
    pub(crate) struct Cutouts {
        pub on: u32,
        pub _pad0: u32,
        pub _pad1: u32,
        pub _pad2: u32,
    }
}

/// A texture reference as the shaders read it: (texture + 1 or 0, UV set) and the rows of
/// its UV transform.
fn tex(r: &Option<TexRef>) -> ([u32; 4], [f32; 4], [f32; 4]) {
    match r {
        Some(r) => {
            let m = r.transform;
            (
                [r.texture as u32 + 1, r.texcoord, 0, 0],
                [m.x_axis.x, m.y_axis.x, m.z_axis.x, 0.0],
                [m.x_axis.y, m.y_axis.y, m.z_axis.y, 0.0],
            )
        }
        None => ([0; 4], [1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]),
    }
}

/// The scene's texturing data on the GPU, constant over an animation (UVs, colours,
/// materials, texels), uploaded once; one-element placeholders for a scene without any.
pub struct TextureData {
    attrs: wgpu::Buffer,
    materials: wgpu::Buffer,
    infos: wgpu::Buffer,
    texels: wgpu::Buffer,
    cut: wgpu::Buffer,
    /// Whether the scene has textures or vertex colours (the `surface` pass runs).
    pub textured: bool,
}

impl TextureData {
    pub fn new(gpu: &Gpu, frame: &Frame) -> Result<Self> {
        let attrs: Vec<TriAttr> = match &frame.attrs {
            Some(a) => (0..frame.tris.len())
                .map(|i| {
                    let [s0, s1] = a.uv[i];
                    let uv = |k: usize| {
                        let (p, q): (Vec2, Vec2) = (s0[k], s1[k]);
                        [p.x, p.y, q.x, q.y]
                    };
                    let c = a.color[i];
                    TriAttr {
                        uv0: uv(0),
                        uv1: uv(1),
                        uv2: uv(2),
                        c0: c[0].to_array(),
                        c1: c[1].to_array(),
                        c2: c[2].to_array(),
                        mat: [frame.tri_material[i], 0, 0, 0],
                    }
                })
                .collect(),
            None => vec![TriAttr::zeroed()],
        };
        let materials: Vec<SurfaceMaterial> = frame
            .materials
            .iter()
            .map(|m| {
                let (base_tex, base_r0, base_r1) = tex(&m.base_color_texture);
                let (emis_tex, emis_r0, emis_r1) = tex(&m.emissive_texture);
                SurfaceMaterial {
                    base_tex: [
                        base_tex[0],
                        base_tex[1],
                        m.alpha.to_bits(),
                        m.alpha_cutoff.unwrap_or(-1.0).to_bits(),
                    ],
                    base_r0,
                    base_r1,
                    emis_tex,
                    emis_r0,
                    emis_r1,
                }
            })
            .chain(std::iter::once(SurfaceMaterial::zeroed()))
            .collect();
        let mut infos = Vec::new();
        let mut texels: Vec<u32> = Vec::new();
        for t in frame.textures.iter() {
            infos.push(TexInfo {
                offset: texels.len() as u32,
                width: t.width,
                height: t.height,
                flags: t.flags(),
            });
            texels.extend(t.texels.iter().map(|&p| u32::from_le_bytes(p)));
        }
        if texels.is_empty() {
            texels.push(0);
            infos.push(TexInfo {
                offset: 0,
                width: 1,
                height: 1,
                flags: 0,
            });
        }
        let limit = gpu.limits.max_storage_buffer_binding_size;
        if bytes::<u32>(texels.len() as u64) > limit {
            bail!(
                "the scene's textures hold {} texels ({} MiB), more than this adapter binds in one buffer ({} MiB)",
                texels.len(),
                (texels.len() * 4) >> 20,
                limit >> 20
            );
        }
        let upload = |label: &str, data: &[u8], usage: wgpu::BufferUsages| {
            let b = gpu.buffer(
                label,
                data.len() as u64,
                usage | wgpu::BufferUsages::COPY_DST,
            );
            gpu.queue.write_buffer(&b, 0, data);
            b
        };
        let storage = wgpu::BufferUsages::STORAGE;
        let cut = Cutouts {
            on: frame.has_cutouts() as u32,
            _pad0: 0,
            _pad1: 0,
            _pad2: 0,
        };
        Ok(TextureData {
            attrs: upload("texture attrs", bytemuck::cast_slice(&attrs), storage),
            materials: upload(
                "texture materials",
                bytemuck::cast_slice(&materials),
                storage,
            ),
            infos: upload("textures", bytemuck::cast_slice(&infos), storage),
            texels: upload("texels", bytemuck::cast_slice(&texels), storage),
            cut: upload("cutouts", bytemuck::bytes_of(&cut), storage),
            textured: frame.attrs.is_some(),
        })
    }

    /// The bindings of `texture.wgsl`'s code, with the triangles: for the passes' tables.
    pub(crate) fn resources<'a>(
        &'a self,
        tris: &'a wgpu::Buffer,
    ) -> [(&'static str, wgpu::BindingResource<'a>); 6] {
        [
            ("cut", self.cut.as_entire_binding()),
            ("tris", tris.as_entire_binding()),
            ("attrs", self.attrs.as_entire_binding()),
            ("materials", self.materials.as_entire_binding()),
            ("textures", self.infos.as_entire_binding()),
            ("texels", self.texels.as_entire_binding()),
        ]
    }
}

/// The surface pass over the scene's texturing data.
pub struct SurfacePass {
    pass: PixelPass,
}

impl SurfacePass {
    /// The pass writing into `surface` (one entry per sample), or None when the scene has
    /// neither textures nor vertex colours.
    pub fn new(
        gpu: &Gpu,
        data: &TextureData,
        params: &wgpu::Buffer,
        tris: &wgpu::Buffer,
        (gbuf, surface): (&wgpu::TextureView, &wgpu::Buffer),
    ) -> Option<Self> {
        if !data.textured {
            return None;
        }
        let [_, tris_r, attrs, materials, textures, texels] = data.resources(tris);
        let pass = PixelPass::new(
            gpu,
            &PASS,
            &[
                ("P", params.as_entire_binding()),
                tris_r,
                ("gbuf", wgpu::BindingResource::TextureView(gbuf)),
                attrs,
                materials,
                textures,
                texels,
                ("surface", surface.as_entire_binding()),
            ],
        );
        Some(SurfacePass { pass })
    }

    pub fn encode(&self, enc: &mut wgpu::CommandEncoder, width: u32, height: u32) {
        self.pass.encode(enc, width, height);
    }
}
