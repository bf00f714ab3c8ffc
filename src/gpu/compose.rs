//! Compose pass (`shaders/compose.wgsl`): emission + direct + indirect into the HDR frame,
//! then exposure and sRGB into the 8-bit preview.

use super::{dispatch, storage_entry, texture_entry, uniform_entry, Gpu};

pub struct Compose {
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    pub hdr: wgpu::Buffer,
    pub ldr: wgpu::Buffer,
}

impl Compose {
    pub fn new(
        gpu: &Gpu,
        params: &wgpu::Buffer,
        tris: &wgpu::Buffer,
        gbuf: &wgpu::TextureView,
        direct: &wgpu::Buffer,
        indirect: &wgpu::Buffer,
        pixels: u64,
    ) -> Self {
        let module = gpu.shader("compose", include_str!("../../shaders/compose.wgsl"));
        let layout = gpu.layout(
            "compose",
            &[
                uniform_entry(0, wgpu::ShaderStages::COMPUTE, false),
                storage_entry(1, true),
                texture_entry(2, wgpu::TextureViewDimension::D2),
                storage_entry(3, true),
                storage_entry(4, true),
                storage_entry(5, false),
                storage_entry(6, false),
            ],
        );
        let pipeline = gpu.compute_pipeline("compose", &module, "main", &[&layout]);
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let hdr = gpu.buffer("hdr", pixels * 16, usage);
        let ldr = gpu.buffer("ldr", pixels * 4, usage);
        let group = gpu.bind(
            "compose",
            &layout,
            &[
                params.as_entire_binding(),
                tris.as_entire_binding(),
                wgpu::BindingResource::TextureView(gbuf),
                direct.as_entire_binding(),
                indirect.as_entire_binding(),
                hdr.as_entire_binding(),
                ldr.as_entire_binding(),
            ],
        );
        Compose {
            pipeline,
            group,
            hdr,
            ldr,
        }
    }

    pub fn encode(&self, enc: &mut wgpu::CommandEncoder, width: u32, height: u32) {
        dispatch(
            enc,
            "compose",
            &self.pipeline,
            &[&self.group],
            (width.div_ceil(8), height.div_ceil(8), 1),
        );
    }
}
