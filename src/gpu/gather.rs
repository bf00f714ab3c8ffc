//! Gather pass (`shaders/gather.wgsl`): indirect light of all VPLs per pixel with ISM
//! visibility. Its CPU twin, with ray-traced visibility, is `reference::twin::gather`.

use super::bindings::{params, read, read_write, texture, Elem, Group, Pass};
use super::common::{FrameConstants, GpuVpl, Surface, Tri};
use super::{Gpu, PixelPass};

pub(crate) const PASS: Pass = Pass {
    name: "gather",
    wgsl: include_str!("../../shaders/gather.wgsl"),
    groups: &[Group {
        stages: wgpu::ShaderStages::COMPUTE,
        bindings: &[
            params("P", &FrameConstants::LAYOUT),
            read("tris", Elem::Struct(&Tri::LAYOUT)),
            read("vpls", Elem::Struct(&GpuVpl::LAYOUT)),
            read("ism", Elem::Plain(4)),
            texture("gbuf", wgpu::TextureViewDimension::D2),
            read_write("indirect", Elem::Plain(16)),
            read("surface", Elem::Struct(&Surface::LAYOUT)),
        ],
    }],
};

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
        (gbuf, surface): (&wgpu::TextureView, &wgpu::Buffer),
        pixels: u64,
    ) -> Self {
        let output = gpu.buffer(
            "indirect",
            super::bindings::bytes::<[f32; 4]>(pixels),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let pass = PixelPass::new(
            gpu,
            &PASS,
            &[
                ("P", params.as_entire_binding()),
                ("tris", tris.as_entire_binding()),
                ("vpls", vpls.as_entire_binding()),
                ("ism", ism.as_entire_binding()),
                ("gbuf", wgpu::BindingResource::TextureView(gbuf)),
                ("surface", surface.as_entire_binding()),
                ("indirect", output.as_entire_binding()),
            ],
        );
        Gather { pass, output }
    }

    /// Gathers the `width` x `height` image; with interleave side `n` > 1 the dispatch covers
    /// the n x n de-interleaved sub-images of ceil(width / n) x ceil(height / n) (see the
    /// shader).
    pub fn encode(&self, enc: &mut wgpu::CommandEncoder, (width, height): (u32, u32), n: u32) {
        let n = n.max(1);
        self.pass
            .encode(enc, width.div_ceil(n) * n, height.div_ceil(n) * n);
    }
}
