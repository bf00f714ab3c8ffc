//! Interleave filter (`shaders/interleave.wgsl`): with `--interleave n > 1` the gather gives
//! each pixel of an n x n block every n^2-th VPL (scaled by n^2, without the albedo), and this
//! pass averages the subsets over the n x n window of pixels on the same surface (depth and
//! normal from the G-buffer), then applies the albedo (Keller & Heidrich 2001; Segovia et
//! al. 2006). `Renderer::interleave_shift` moves the pattern: over a uniformly random shift
//! every pixel's filtered value is an unbiased estimate of the full gather.

use super::bindings::{bytes, params, read, read_write, texture, Elem, Group, Pass};
use super::common::{FrameConstants, Surface, Tri};
use super::{Gpu, PixelPass};

pub(crate) const PASS: Pass = Pass {
    name: "interleave",
    wgsl: include_str!("../../shaders/interleave.wgsl"),
    groups: &[Group {
        stages: wgpu::ShaderStages::COMPUTE,
        bindings: &[
            params("P", &FrameConstants::LAYOUT),
            read("tris", Elem::Struct(&Tri::LAYOUT)),
            texture("gbuf", wgpu::TextureViewDimension::D2),
            read("subsets", Elem::Plain(16)),
            read_write("indirect", Elem::Plain(16)),
            read("surface", Elem::Struct(&Surface::LAYOUT)),
        ],
    }],
};

pub struct Interleave {
    pass: PixelPass,
    /// The filtered indirect light (albedo applied), as the full gather's output.
    pub output: wgpu::Buffer,
}

impl Interleave {
    pub fn new(
        gpu: &Gpu,
        params: &wgpu::Buffer,
        tris: &wgpu::Buffer,
        (gbuf, surface): (&wgpu::TextureView, &wgpu::Buffer),
        subsets: &wgpu::Buffer,
        pixels: u64,
    ) -> Self {
        let output = gpu.buffer(
            "indirect filtered",
            bytes::<[f32; 4]>(pixels),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let pass = PixelPass::new(
            gpu,
            &PASS,
            &[
                ("P", params.as_entire_binding()),
                ("tris", tris.as_entire_binding()),
                ("gbuf", wgpu::BindingResource::TextureView(gbuf)),
                ("surface", surface.as_entire_binding()),
                ("subsets", subsets.as_entire_binding()),
                ("indirect", output.as_entire_binding()),
            ],
        );
        Interleave { pass, output }
    }

    pub fn encode(&self, enc: &mut wgpu::CommandEncoder, width: u32, height: u32) {
        self.pass.encode(enc, width, height);
    }
}
