//! Compose pass (`shaders/compose.wgsl`): emission + direct + indirect into the HDR frame,
//! then exposure and sRGB into the 8-bit preview.

use super::{storage_entry, texture_entry, uniform_entry, Gpu, PixelPass};

pub struct Compose {
    pass: PixelPass,
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
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let hdr = gpu.buffer("hdr", pixels * 16, usage);
        let ldr = gpu.buffer("ldr", pixels * 4, usage);
        let pass = PixelPass::new(
            gpu,
            "compose",
            include_str!("../../shaders/compose.wgsl"),
            &[
                uniform_entry(0, wgpu::ShaderStages::COMPUTE, false),
                storage_entry(1, true),
                texture_entry(2, wgpu::TextureViewDimension::D2),
                storage_entry(3, true),
                storage_entry(4, true),
                storage_entry(5, false),
                storage_entry(6, false),
            ],
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
        Compose { pass, hdr, ldr }
    }

    pub fn encode(&self, enc: &mut wgpu::CommandEncoder, width: u32, height: u32) {
        self.pass.encode(enc, width, height);
    }
}
