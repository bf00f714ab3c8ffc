//! G-buffer pass (`shaders/gbuffer.wgsl`): the camera's view rasterized into world position
//! and triangle index per pixel, at pixel centres.

use super::bindings::{gpu_struct, Group, Pass};
use super::Gpu;
use glam::Mat4;

pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

gpu_struct! {
    /// The camera's view-projection matrix (column-major).
    pub(crate) struct Camera {
        pub view_proj: [[f32; 4]; 4],
    }
}

pub(crate) const PASS: Pass = Pass {
    name: "gbuffer",
    wgsl: include_str!("../../shaders/gbuffer.wgsl"),
    groups: &[Group {
        stages: wgpu::ShaderStages::VERTEX,
        bindings: &[super::bindings::uniform("cam", &Camera::LAYOUT)],
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

pub struct GBuffer {
    pipeline: wgpu::RenderPipeline,
    uniform: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    pub view: wgpu::TextureView,
    depth: wgpu::TextureView,
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
    pub fn new(gpu: &Gpu, width: u32, height: u32) -> Self {
        let module = PASS.module(gpu);
        let layout = PASS.groups[0].layout(gpu, PASS.name);
        let pipeline = gpu.raster_pipeline(PASS.name, &module, &layout, FORMAT);
        let uniform = gpu.buffer(
            "gbuffer camera",
            std::mem::size_of::<Camera>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let bind_group = PASS.groups[0].bind(
            gpu,
            PASS.name,
            &layout,
            &[("cam", uniform.as_entire_binding())],
        );
        let view =
            target(gpu, "gbuffer", width, height, 1, FORMAT, true).create_view(&Default::default());
        let depth = target(
            gpu,
            "gbuffer depth",
            width,
            height,
            1,
            wgpu::TextureFormat::Depth32Float,
            false,
        )
        .create_view(&Default::default());
        GBuffer {
            pipeline,
            uniform,
            bind_group,
            view,
            depth,
        }
    }

    pub fn encode(
        &self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        vertices: &wgpu::Buffer,
        count: u32,
        view_proj: Mat4,
    ) {
        let cam = Camera {
            view_proj: view_proj.to_cols_array_2d(),
        };
        gpu.queue
            .write_buffer(&self.uniform, 0, bytemuck::bytes_of(&cam));
        raster(
            enc,
            "gbuffer",
            &self.pipeline,
            &self.bind_group,
            &[],
            &self.view,
            &self.depth,
            vertices,
            count,
        );
    }
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
    let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
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
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind_group, offsets);
    pass.set_vertex_buffer(0, vertices.slice(..));
    pass.draw(0..count, 0..1);
}
