//! Gather pass (`shaders/gather.wgsl`): indirect light of all VPLs per pixel with ISM
//! visibility. Its CPU twin, with ray-traced visibility, is `reference::twin::gather`.

use super::{dispatch, storage_entry, texture_entry, uniform_entry, Gpu};

pub struct Gather {
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    pub output: wgpu::Buffer,
}

impl Gather {
    pub fn new(
        gpu: &Gpu,
        params: &wgpu::Buffer,
        tris: &wgpu::Buffer,
        vpls: &wgpu::Buffer,
        ism: &wgpu::Buffer,
        gbuf: &wgpu::TextureView,
        pixels: u64,
    ) -> Self {
        let module = gpu.shader("gather", include_str!("../../shaders/gather.wgsl"));
        let layout = gpu.layout(
            "gather",
            &[
                uniform_entry(0, wgpu::ShaderStages::COMPUTE, false),
                storage_entry(1, true),
                storage_entry(2, true),
                storage_entry(3, true),
                texture_entry(4, wgpu::TextureViewDimension::D2),
                storage_entry(5, false),
            ],
        );
        let pipeline = gpu.compute_pipeline("gather", &module, "main", &[&layout]);
        let output = gpu.buffer(
            "indirect",
            pixels * 16,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let group = gpu.bind(
            "gather",
            &layout,
            &[
                params.as_entire_binding(),
                tris.as_entire_binding(),
                vpls.as_entire_binding(),
                ism.as_entire_binding(),
                wgpu::BindingResource::TextureView(gbuf),
                output.as_entire_binding(),
            ],
        );
        Gather {
            pipeline,
            group,
            output,
        }
    }

    pub fn encode(&self, enc: &mut wgpu::CommandEncoder, width: u32, height: u32) {
        dispatch(
            enc,
            "gather",
            &self.pipeline,
            &[&self.group],
            (width.div_ceil(8), height.div_ceil(8), 1),
        );
    }
}
