//! Direct-light pass (`shaders/direct.wgsl`): stratified emitter samples with shadow
//! hemicube visibility. Its CPU twin is `reference::twin::direct`.

use super::{dispatch, storage_entry, texture_entry, uniform_entry, Gpu};

pub struct Direct {
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    pub output: wgpu::Buffer,
}

impl Direct {
    pub fn new(
        gpu: &Gpu,
        params: &wgpu::Buffer,
        tris: &wgpu::Buffer,
        lights: &wgpu::Buffer,
        shadows: &wgpu::TextureView,
        gbuf: &wgpu::TextureView,
        pixels: u64,
    ) -> Self {
        let module = gpu.shader("direct", include_str!("../../shaders/direct.wgsl"));
        let layout = gpu.layout(
            "direct",
            &[
                uniform_entry(0, wgpu::ShaderStages::COMPUTE, false),
                storage_entry(1, true),
                storage_entry(2, true),
                texture_entry(3, wgpu::TextureViewDimension::D2Array),
                texture_entry(4, wgpu::TextureViewDimension::D2),
                storage_entry(5, false),
            ],
        );
        let pipeline = gpu.compute_pipeline("direct", &module, "main", &[&layout]);
        let output = gpu.buffer(
            "direct",
            pixels * 16,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let group = gpu.bind(
            "direct",
            &layout,
            &[
                params.as_entire_binding(),
                tris.as_entire_binding(),
                lights.as_entire_binding(),
                wgpu::BindingResource::TextureView(shadows),
                wgpu::BindingResource::TextureView(gbuf),
                output.as_entire_binding(),
            ],
        );
        Direct {
            pipeline,
            group,
            output,
        }
    }

    pub fn encode(&self, enc: &mut wgpu::CommandEncoder, width: u32, height: u32) {
        dispatch(
            enc,
            "direct",
            &self.pipeline,
            &[&self.group],
            (width.div_ceil(8), height.div_ceil(8), 1),
        );
    }
}
