//! Direct-light pass (`shaders/direct.wgsl`): stratified emitter samples with shadow
//! hemicube visibility. Its CPU twin is `reference::twin::direct`.

use super::bindings::{params, read, read_write, texture, Elem, Group, Pass};
use super::common::{LightSample, Params, Tri};
use super::{Gpu, PixelPass};

pub(crate) const PASS: Pass = Pass {
    name: "direct",
    wgsl: include_str!("../../shaders/direct.wgsl"),
    groups: &[Group {
        stages: wgpu::ShaderStages::COMPUTE,
        bindings: &[
            params("P", &Params::LAYOUT),
            read("tris", Elem::Struct(&Tri::LAYOUT)),
            read("lights", Elem::Struct(&LightSample::LAYOUT)),
            texture("shadows", wgpu::TextureViewDimension::D2Array),
            texture("gbuf", wgpu::TextureViewDimension::D2),
            read_write("direct", Elem::Plain(16)),
        ],
    }],
};

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
            super::bindings::bytes::<[f32; 4]>(pixels),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let pass = PixelPass::new(
            gpu,
            &PASS,
            &[
                ("P", params.as_entire_binding()),
                ("tris", tris.as_entire_binding()),
                ("lights", lights.as_entire_binding()),
                ("shadows", wgpu::BindingResource::TextureView(shadows)),
                ("gbuf", wgpu::BindingResource::TextureView(gbuf)),
                ("direct", output.as_entire_binding()),
            ],
        );
        Direct { pass, output }
    }

    pub fn encode(&self, enc: &mut wgpu::CommandEncoder, width: u32, height: u32) {
        self.pass.encode(enc, width, height);
    }
}
