//! G-buffer pass (`shaders/gbuffer.wgsl`): the camera's view rasterized into world position
//! and triangle index per sample. With `aa = 1` the samples are the pixel centres; with
//! supersampling (`aa = S`) the target holds S x S tiles, each the whole image sampled at one
//! offset inside every pixel ([`subsample`]): tile (i, j) is drawn with the projection moved
//! by that offset ([`jittered`]) into its own viewport (see docs/antialiasing.md).

use super::bindings::{gpu_struct, Elem, Group, Pass};
use super::common::Tri;
use super::Gpu;
use crate::scene::culling::{CullView, Draw};
use glam::{Mat4, Vec2, Vec3};

pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

gpu_struct! {
    /// The camera's view-projection matrix (column-major) and its position (single-sided
    /// triangles seen from behind are left out).
    pub(crate) struct Camera {
        pub view_proj: [[f32; 4]; 4],
        pub eye: [f32; 4],
    }
}

pub(crate) const PASS: Pass = Pass {
    name: "gbuffer",
    wgsl: concat!(
        include_str!("../../shaders/texture.wgsl"),
        include_str!("../../shaders/gbuffer.wgsl")
    ),
    // The texturing data: alpha MASK cut-outs are discarded (see `texture.wgsl`).
    groups: &[Group {
        stages: wgpu::ShaderStages::VERTEX_FRAGMENT,
        bindings: &[
            super::bindings::dynamic_uniform("cam", &Camera::LAYOUT),
            super::bindings::params("cut", &super::surface::Cutouts::LAYOUT),
            super::bindings::read("tris", Elem::Struct(&Tri::LAYOUT)),
            super::bindings::read("attrs", Elem::Struct(&super::surface::TriAttr::LAYOUT)),
            super::bindings::read(
                "materials",
                Elem::Struct(&super::surface::SurfaceMaterial::LAYOUT),
            ),
            super::bindings::read("textures", Elem::Struct(&super::surface::TexInfo::LAYOUT)),
            super::bindings::read("texels", Elem::Plain(4)),
        ],
    }],
};

/// One vertex of the scene's vertex buffer (shared by the G-buffer and shadow passes):
/// position and the index of its triangle.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Vertex {
    pub pos: [f32; 3],
    pub tri: u32,
}

impl Vertex {
    /// The vertex buffer's layout over `attributes` (see [`Vertex::ATTRIBUTES`]).
    pub(crate) fn layout(attributes: &[wgpu::VertexAttribute]) -> wgpu::VertexBufferLayout<'_> {
        wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<Vertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes,
        }
    }

    /// Locations 0 and 1 of the `vs` entry points.
    pub(crate) const ATTRIBUTES: [wgpu::VertexAttribute; 2] = [
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: std::mem::offset_of!(Vertex, pos) as u64,
            shader_location: 0,
        },
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Uint32,
            offset: std::mem::offset_of!(Vertex, tri) as u64,
            shader_location: 1,
        },
    ];
}

pub use crate::scene::camera::subsample;

/// `view_proj` for a `width x height` viewport moved so that its pixel centres sample the
/// image at offset `o` (see [`subsample`]) inside each pixel instead of at the centre.
pub fn jittered(view_proj: Mat4, o: Vec2, width: u32, height: u32) -> Mat4 {
    // Clip-space x and y move by the offset in NDC units (times w), y up in NDC.
    let d = Vec3::new(
        2.0 * (0.5 - o.x) / width as f32,
        -2.0 * (0.5 - o.y) / height as f32,
        0.0,
    );
    Mat4::from_translation(d) * view_proj
}

/// Bytes from one uniform to the next at dynamic offsets (the adapter's alignment).
pub(crate) fn uniform_stride<T>(gpu: &Gpu) -> u64 {
    (std::mem::size_of::<T>() as u64)
        .next_multiple_of(gpu.limits.min_uniform_buffer_offset_alignment as u64)
}

/// The pipelines of one raster pass by the faces they skip: none, the back ones, the front
/// ones (for a view whose projection mirrors, where a solid's back faces are the ones that
/// turn counter-clockwise; see [`skipped_faces`]).
pub(crate) struct Pipelines([wgpu::RenderPipeline; 3]);

impl Pipelines {
    pub(crate) fn new(
        gpu: &Gpu,
        label: &str,
        (module, layout): (&wgpu::ShaderModule, &wgpu::BindGroupLayout),
        target: wgpu::TextureFormat,
        vertices: wgpu::VertexBufferLayout,
        entries: (&str, &str),
    ) -> Self {
        Pipelines(
            [None, Some(wgpu::Face::Back), Some(wgpu::Face::Front)].map(|cull| {
                gpu.raster_pipeline_over(
                    label,
                    module,
                    layout,
                    target,
                    vertices.clone(),
                    entries,
                    cull,
                )
            }),
        )
    }

    /// Draws the triangles of `runs` (vertices `3 start .. 3 end`, or indices if `indexed`)
    /// as each says ([`crate::scene::culling::CullView::runs`]): `Front` runs skipping the faces
    /// `skip` names, `All` runs every face.
    pub(crate) fn draw(
        &self,
        pass: &mut wgpu::RenderPass,
        runs: &[(std::ops::Range<u32>, Draw)],
        skip: wgpu::Face,
        indexed: bool,
    ) {
        for (r, d) in runs {
            let p = match (d, skip) {
                (Draw::Front, wgpu::Face::Back) => &self.0[1],
                (Draw::Front, wgpu::Face::Front) => &self.0[2],
                _ => &self.0[0],
            };
            pass.set_pipeline(p);
            let v = 3 * r.start..3 * r.end;
            if indexed {
                pass.draw_indexed(v, 0, 0..1);
            } else {
                pass.draw(v, 0..1);
            }
        }
    }
}

/// The faces a view skips on a solid seen from outside: its back faces, which the raster
/// sees turn counter-clockwise (`wgpu::Face::Front` to the pipeline) where the projection
/// mirrors. The view maps a point `p` to clip `x = r.p + .., y = u.p + .., w = f.p + ..` (or,
/// orthographic, `w` constant and `f` the viewing direction): a triangle facing the eye,
/// counter-clockwise seen from it, keeps that turn in normalized device coordinates exactly
/// when `(r x u).f < 0` (see docs/math.md, "What the raster passes leave out").
pub(crate) fn skipped_faces(r: Vec3, u: Vec3, f: Vec3) -> wgpu::Face {
    if r.cross(u).dot(f) < 0.0 {
        wgpu::Face::Back
    } else {
        wgpu::Face::Front
    }
}

/// The G-buffer camera's [`skipped_faces`] and [`CullView`] on a `width x height` image: the
/// near plane (clip `z >= 0`) and the four side planes (`|x|, |y| <= w`), widened by a pixel
/// on each side (twice the half pixel a sub-sample tile's jitter moves them) so that every
/// tile's frustum lies inside.
pub(crate) fn camera_view(view_proj: Mat4, width: u32, height: u32) -> (wgpu::Face, CullView) {
    let row = |i: usize| view_proj.row(i);
    let plane = |v: glam::Vec4| (v.truncate(), v.w);
    let skip = skipped_faces(row(0).truncate(), row(1).truncate(), row(3).truncate());
    let (kx, ky) = (1.0 + 2.0 / width as f32, 1.0 + 2.0 / height as f32);
    let sides = vec![
        plane(row(3) * kx - row(0)),
        plane(row(3) * kx + row(0)),
        plane(row(3) * ky - row(1)),
        plane(row(3) * ky + row(1)),
    ];
    (
        skip,
        CullView {
            near: plane(row(2)),
            sides,
        },
    )
}

pub struct GBuffer {
    pipelines: Pipelines,
    uniform: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    pub view: wgpu::TextureView,
    depth: wgpu::TextureView,
    /// Output size and sub-samples per pixel side (the target is `aa` times the size).
    width: u32,
    height: u32,
    aa: u32,
    stride: u64,
}

pub(crate) fn target(
    gpu: &Gpu,
    label: &str,
    w: u32,
    h: u32,
    layers: u32,
    format: wgpu::TextureFormat,
    sampled: bool,
) -> wgpu::Texture {
    let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
    if sampled {
        usage |= wgpu::TextureUsages::TEXTURE_BINDING;
    }
    gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

impl GBuffer {
    /// The G-buffer of a `width x height` image with `aa x aa` sub-samples per pixel;
    /// `plain`: the scene has no cut-outs, so no fragment is discarded: the pass draws with
    /// `vs_sided` and `fs_plain` (single-sided triangles seen from behind left out by the
    /// vertex stage), else with `vs` and `fs` (both tests in the fragment stage).
    pub fn new(
        gpu: &Gpu,
        (width, height, aa): (u32, u32, u32),
        textures: &super::surface::TextureData,
        tris: &wgpu::Buffer,
        plain: bool,
    ) -> Self {
        let module = PASS.module(gpu);
        let layout = PASS.groups[0].layout(gpu, PASS.name);
        let attributes = Vertex::ATTRIBUTES;
        let pipelines = Pipelines::new(
            gpu,
            PASS.name,
            (&module, &layout),
            FORMAT,
            Vertex::layout(&attributes),
            if plain {
                ("vs_sided", "fs_plain")
            } else {
                ("vs", "fs")
            },
        );
        let stride = uniform_stride::<Camera>(gpu);
        let uniform = gpu.buffer(
            "gbuffer cameras",
            stride * (aa * aa) as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let cam = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &uniform,
            offset: 0,
            size: wgpu::BufferSize::new(std::mem::size_of::<Camera>() as u64),
        });
        let mut resources = vec![("cam", cam)];
        resources.extend(textures.resources(tris));
        let bind_group = PASS.groups[0].bind(gpu, PASS.name, &layout, &resources);
        let (gw, gh) = (width * aa, height * aa);
        let view = target(gpu, "gbuffer", gw, gh, 1, FORMAT, true).create_view(&Default::default());
        let depth = target(
            gpu,
            "gbuffer depth",
            gw,
            gh,
            1,
            wgpu::TextureFormat::Depth32Float,
            false,
        )
        .create_view(&Default::default());
        GBuffer {
            pipelines,
            uniform,
            bind_group,
            view,
            depth,
            width,
            height,
            aa,
            stride,
        }
    }

    /// Draws the triangles of `runs` (see [`CullView::runs`]) seen by `view_proj`, culling the
    /// faces `skip` names in the `Front` runs (both from [`camera_view`]): the `vertices`
    /// themselves (3 a triangle), or through `indices` into them where given.
    pub fn encode(
        &self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        (vertices, indices): (&wgpu::Buffer, Option<&wgpu::Buffer>),
        runs: &[(std::ops::Range<u32>, Draw)],
        (view_proj, skip, eye): (Mat4, wgpu::Face, Vec3),
    ) {
        let (s, w, h) = (self.aa, self.width, self.height);
        let mut bytes = vec![0u8; self.stride as usize * (s * s) as usize];
        let mut tiles = Vec::new();
        for j in 0..s {
            for i in 0..s {
                let k = (j * s + i) as usize;
                let cam = Camera {
                    view_proj: jittered(view_proj, subsample(i, j, s), w, h).to_cols_array_2d(),
                    eye: eye.extend(1.0).to_array(),
                };
                let o = k * self.stride as usize;
                bytes[o..o + std::mem::size_of::<Camera>()]
                    .copy_from_slice(bytemuck::bytes_of(&cam));
                tiles.push(((k as u64 * self.stride) as u32, [i * w, j * h, w, h]));
            }
        }
        gpu.queue.write_buffer(&self.uniform, 0, &bytes);
        raster_tiles(
            enc,
            "gbuffer",
            &self.bind_group,
            &tiles,
            (&self.view, &self.depth),
            vertices,
            |pass| {
                if let Some(b) = indices {
                    pass.set_index_buffer(b.slice(..), wgpu::IndexFormat::Uint32);
                }
                self.pipelines.draw(pass, runs, skip, indices.is_some())
            },
        );
    }
}

/// One render pass over the scene's triangles into a colour view and a depth view, `draw`n
/// (pipeline and draw calls) once per tile: (dynamic offset of its uniform, viewport x, y,
/// width, height).
pub(crate) fn raster_tiles(
    enc: &mut wgpu::CommandEncoder,
    label: &str,
    bind_group: &wgpu::BindGroup,
    tiles: &[(u32, [u32; 4])],
    (color, depth): (&wgpu::TextureView, &wgpu::TextureView),
    vertices: &wgpu::Buffer,
    draw: impl Fn(&mut wgpu::RenderPass),
) {
    let mut pass = begin(enc, label, color, depth);
    pass.set_vertex_buffer(0, vertices.slice(..));
    for &(offset, [x, y, w, h]) in tiles {
        pass.set_bind_group(0, bind_group, &[offset]);
        pass.set_viewport(x as f32, y as f32, w as f32, h as f32, 0.0, 1.0);
        pass.set_scissor_rect(x, y, w, h);
        draw(&mut pass);
    }
}

/// A render pass clearing `color` (to zero: no surface) and `depth` (to the far plane).
pub(crate) fn begin<'a>(
    enc: &'a mut wgpu::CommandEncoder,
    label: &str,
    color: &wgpu::TextureView,
    depth: &wgpu::TextureView,
) -> wgpu::RenderPass<'a> {
    enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: color,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(1.0),
                store: wgpu::StoreOp::Discard,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// One render pass over the scene's triangles into a colour view and a depth view.
#[allow(clippy::too_many_arguments)]
pub(crate) fn raster(
    enc: &mut wgpu::CommandEncoder,
    label: &str,
    pipeline: &wgpu::RenderPipeline,
    bind_group: &wgpu::BindGroup,
    offsets: &[u32],
    color: &wgpu::TextureView,
    depth: &wgpu::TextureView,
    vertices: &wgpu::Buffer,
    count: u32,
) {
    let mut pass = begin(enc, label, color, depth);
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind_group, offsets);
    pass.set_vertex_buffer(0, vertices.slice(..));
    pass.draw(0..count, 0..1);
}
