//! Compose pass (`shaders/compose.wgsl`): emission + direct + indirect into the HDR frame,
//! then exposure and sRGB into the 8-bit preview.

use super::bindings::{bytes, params, read, read_write, texture, Elem, Group, Pass};
use super::common::{FrameConstants, Surface, Tri};
use super::{Gpu, PixelPass};

pub(crate) const PASS: Pass = Pass {
    name: "compose",
    wgsl: include_str!("../../shaders/compose.wgsl"),
    groups: &[Group {
        stages: wgpu::ShaderStages::COMPUTE,
        bindings: &[
            params("P", &FrameConstants::LAYOUT),
            read("tris", Elem::Struct(&Tri::LAYOUT)),
            texture("gbuf", wgpu::TextureViewDimension::D2),
            read("direct", Elem::Plain(16)),
            read("indirect", Elem::Plain(16)),
            read_write("hdr", Elem::Plain(16)),
            read_write("ldr", Elem::Plain(4)),
            read_write("indirect_ss", Elem::Plain(16)),
            read("surface", Elem::Struct(&Surface::LAYOUT)),
        ],
    }],
};

pub struct Compose {
    pass: PixelPass,
    pub hdr: wgpu::Buffer,
    pub ldr: wgpu::Buffer,
    /// Supersampled (`aa > 1`): each sub-sample's indirect light, for the downsample (else a
    /// placeholder of 16 bytes).
    pub indirect_ss: wgpu::Buffer,
}

impl Compose {
    /// Composes `pixels` samples from the direct and indirect light; `supersampled`: the
    /// samples are the sub-samples of `--aa` > 1 and the indirect light is per pixel.
    pub fn new(
        gpu: &Gpu,
        params: &wgpu::Buffer,
        tris: &wgpu::Buffer,
        (gbuf, surface): (&wgpu::TextureView, &wgpu::Buffer),
        (direct, indirect): (&wgpu::Buffer, &wgpu::Buffer),
        pixels: u64,
        supersampled: bool,
    ) -> Self {
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let hdr = gpu.buffer("hdr", bytes::<[f32; 4]>(pixels), usage);
        let ldr = gpu.buffer("ldr", bytes::<u32>(pixels), usage);
        let ss = if supersampled { pixels } else { 1 };
        let indirect_ss = gpu.buffer("indirect per sub-sample", bytes::<[f32; 4]>(ss), usage);
        let pass = PixelPass::new(
            gpu,
            &PASS,
            &[
                ("P", params.as_entire_binding()),
                ("tris", tris.as_entire_binding()),
                ("gbuf", wgpu::BindingResource::TextureView(gbuf)),
                ("surface", surface.as_entire_binding()),
                ("direct", direct.as_entire_binding()),
                ("indirect", indirect.as_entire_binding()),
                ("hdr", hdr.as_entire_binding()),
                ("ldr", ldr.as_entire_binding()),
                ("indirect_ss", indirect_ss.as_entire_binding()),
            ],
        );
        Compose {
            pass,
            hdr,
            ldr,
            indirect_ss,
        }
    }

    pub fn encode(&self, enc: &mut wgpu::CommandEncoder, width: u32, height: u32) {
        self.pass.encode(enc, width, height);
    }
}
