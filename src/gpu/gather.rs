//! Gather pass (`shaders/gather.wgsl`): indirect light of all VPLs per pixel with ISM
//! visibility. Its CPU twin, with ray-traced visibility, is `reference::twin::gather`.

use super::{storage_entry, texture_entry, uniform_entry, Gpu, PixelPass};

pub struct Gather {
    pass: PixelPass,
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
        let output = gpu.buffer(
            "indirect",
            pixels * 16,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let pass = PixelPass::new(
            gpu,
            "gather",
            include_str!("../../shaders/gather.wgsl"),
            &[
                uniform_entry(0, wgpu::ShaderStages::COMPUTE, false),
                storage_entry(1, true),
                storage_entry(2, true),
                storage_entry(3, true),
                texture_entry(4, wgpu::TextureViewDimension::D2),
                storage_entry(5, false),
            ],
            &[
                params.as_entire_binding(),
                tris.as_entire_binding(),
                vpls.as_entire_binding(),
                ism.as_entire_binding(),
                wgpu::BindingResource::TextureView(gbuf),
                output.as_entire_binding(),
            ],
        );
        Gather { pass, output }
    }

    pub fn encode(&self, enc: &mut wgpu::CommandEncoder, width: u32, height: u32) {
        self.pass.encode(enc, width, height);
    }
}
