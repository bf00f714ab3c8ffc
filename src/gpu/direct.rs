//! Direct-light pass (`shaders/direct.wgsl`): stratified emitter samples with shadow
//! hemicube visibility. Its CPU twin is `reference::twin::direct`.

use super::{storage_entry, texture_entry, uniform_entry, Gpu, PixelPass};

pub struct Direct {
    pass: PixelPass,
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
        let output = gpu.buffer(
            "direct",
            pixels * 16,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let pass = PixelPass::new(
            gpu,
            "direct",
            include_str!("../../shaders/direct.wgsl"),
            &[
                uniform_entry(0, wgpu::ShaderStages::COMPUTE, false),
                storage_entry(1, true),
                storage_entry(2, true),
                texture_entry(3, wgpu::TextureViewDimension::D2Array),
                texture_entry(4, wgpu::TextureViewDimension::D2),
                storage_entry(5, false),
            ],
            &[
                params.as_entire_binding(),
                tris.as_entire_binding(),
                lights.as_entire_binding(),
                wgpu::BindingResource::TextureView(shadows),
                wgpu::BindingResource::TextureView(gbuf),
                output.as_entire_binding(),
            ],
        );
        Direct { pass, output }
    }

    pub fn encode(&self, enc: &mut wgpu::CommandEncoder, width: u32, height: u32) {
        self.pass.encode(enc, width, height);
    }
}
