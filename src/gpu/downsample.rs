//! Downsample pass (`shaders/downsample.wgsl`), with supersampling (`--aa S` > 1): every pass
//! before it ran on S x S sub-samples per pixel; each output pixel is the box-filtered mean
//! of its sub-samples, for the HDR frame, its direct and indirect parts, and the 8-bit
//! preview (see docs/antialiasing.md).

use super::bindings::{bytes, params, read, read_write, Elem, Group, Pass};
use super::common::FrameConstants;
use super::{Gpu, PixelPass};

pub(crate) const PASS: Pass = Pass {
    name: "downsample",
    wgsl: include_str!("../../shaders/downsample.wgsl"),
    groups: &[Group {
        stages: wgpu::ShaderStages::COMPUTE,
        bindings: &[
            params("P", &FrameConstants::LAYOUT),
            read("hdr_in", Elem::Plain(16)),
            read("direct_in", Elem::Plain(16)),
            read("indirect_in", Elem::Plain(16)),
            read_write("hdr", Elem::Plain(16)),
            read_write("ldr", Elem::Plain(4)),
            read_write("direct", Elem::Plain(16)),
            read_write("indirect", Elem::Plain(16)),
        ],
    }],
};

/// The resolved frame at the output size.
pub struct Downsample {
    pass: PixelPass,
    pub hdr: wgpu::Buffer,
    pub ldr: wgpu::Buffer,
    pub direct: wgpu::Buffer,
    pub indirect: wgpu::Buffer,
}

impl Downsample {
    /// Resolves the sub-sample buffers `hdr`, `direct` and `indirect` into buffers of
    /// `pixels` output pixels.
    pub fn new(
        gpu: &Gpu,
        params: &wgpu::Buffer,
        (hdr_in, direct_in, indirect_in): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
        pixels: u64,
    ) -> Self {
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let hdr = gpu.buffer("resolved hdr", bytes::<[f32; 4]>(pixels), usage);
        let ldr = gpu.buffer("resolved ldr", bytes::<u32>(pixels), usage);
        let direct = gpu.buffer("resolved direct", bytes::<[f32; 4]>(pixels), usage);
        let indirect = gpu.buffer("resolved indirect", bytes::<[f32; 4]>(pixels), usage);
        let pass = PixelPass::new(
            gpu,
            &PASS,
            &[
                ("P", params.as_entire_binding()),
                ("hdr_in", hdr_in.as_entire_binding()),
                ("direct_in", direct_in.as_entire_binding()),
                ("indirect_in", indirect_in.as_entire_binding()),
                ("hdr", hdr.as_entire_binding()),
                ("ldr", ldr.as_entire_binding()),
                ("direct", direct.as_entire_binding()),
                ("indirect", indirect.as_entire_binding()),
            ],
        );
        Downsample {
            pass,
            hdr,
            ldr,
            direct,
            indirect,
        }
    }

    /// Dispatches over the output's `width x height` pixels.
    pub fn encode(&self, enc: &mut wgpu::CommandEncoder, width: u32, height: u32) {
        self.pass.encode(enc, width, height);
    }
}
