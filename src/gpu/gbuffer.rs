//! G-buffer pass (`shaders/gbuffer.wgsl`): the camera's view rasterized into world position
//! and triangle index per pixel, at pixel centres.

use super::Gpu;
use glam::Mat4;

pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

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
        let module = gpu.shader("gbuffer", include_str!("../../shaders/gbuffer.wgsl"));
        let layout = gpu.layout(
            "gbuffer",
            &[super::uniform_entry(0, wgpu::ShaderStages::VERTEX, false)],
        );
        let pipeline = gpu.raster_pipeline("gbuffer", &module, &layout, FORMAT);
        let uniform = gpu.buffer(
            "gbuffer camera",
            64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let bind_group = gpu.bind("gbuffer", &layout, &[uniform.as_entire_binding()]);
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
        gpu.queue
            .write_buffer(&self.uniform, 0, bytemuck::bytes_of(&view_proj));
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
