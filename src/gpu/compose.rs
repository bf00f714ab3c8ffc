//! Compose pass (`shaders/compose.wgsl`): emission + direct + indirect into the HDR frame,
//! then exposure and sRGB into the 8-bit preview.

use super::bindings::{bytes, params, read, read_write, texture, Elem, Group, Pass};
use super::common::{Params, Tri};
use super::{Gpu, PixelPass};

pub(crate) const PASS: Pass = Pass {
    name: "compose",
    wgsl: include_str!("../../shaders/compose.wgsl"),
    groups: &[Group {
        stages: wgpu::ShaderStages::COMPUTE,
        bindings: &[
            params("P", &Params::LAYOUT),
            read("tris", Elem::Struct(&Tri::LAYOUT)),
            texture("gbuf", wgpu::TextureViewDimension::D2),
            read("direct", Elem::Plain(16)),
            read("indirect", Elem::Plain(16)),
            read_write("hdr", Elem::Plain(16)),
            read_write("ldr", Elem::Plain(4)),
        ],
    }],
};

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
        let hdr = gpu.buffer("hdr", bytes::<[f32; 4]>(pixels), usage);
        let ldr = gpu.buffer("ldr", bytes::<u32>(pixels), usage);
        let pass = PixelPass::new(
            gpu,
            &PASS,
            &[
                ("P", params.as_entire_binding()),
                ("tris", tris.as_entire_binding()),
                ("gbuf", wgpu::BindingResource::TextureView(gbuf)),
                ("direct", direct.as_entire_binding()),
                ("indirect", indirect.as_entire_binding()),
                ("hdr", hdr.as_entire_binding()),
                ("ldr", ldr.as_entire_binding()),
            ],
        );
        Compose { pass, hdr, ldr }
    }

    pub fn encode(&self, enc: &mut wgpu::CommandEncoder, width: u32, height: u32) {
        self.pass.encode(enc, width, height);
    }
}
