//! Direct-light pass (`shaders/direct.wgsl`): stratified emitter samples with shadow
//! hemicube visibility, and punctual lights: half a point light or a spot with a hemicube
//! too, a directional light with an orthographic map (see `shadow`). Its CPU twin is
//! `reference::twin::direct`.

use super::bindings::{params, read, read_write, texture, Elem, Group, Pass};
use super::common::{FrameConstants, GpuEmitterSample, Surface, Tri};
use super::{Gpu, PixelPass};
use crate::scene::{EmitterSample, SampleKind};

/// A light sample's kind code in `pos.w` (as `shaders/direct.wgsl` reads it).
pub const KIND_AREA: f32 = 0.0;
pub const KIND_POINT_HALF: f32 = 1.0;
pub const KIND_SPOT: f32 = 2.0;
pub const KIND_DIRECTIONAL: f32 = 3.0;
pub const KIND_POINT_CONE: f32 = 4.0;

impl GpuEmitterSample {
    /// Position, normal and radiance, with the kind in `pos.w` and its parameters in
    /// `normal.w` and `radiance.w` (a spot's inner and outer cosines, a directional
    /// light's map half-extent, a far point light's frustum half-width), and its shadow
    /// map's window on maps of `shadow_size` texels.
    pub(crate) fn of(l: &EmitterSample, lit: (glam::Vec3, glam::Vec3), shadow_size: u32) -> Self {
        let (kind, a, b) = match l.kind {
            SampleKind::Area => (KIND_AREA, 0.0, 0.0),
            SampleKind::PointHalf => (KIND_POINT_HALF, 0.0, 0.0),
            SampleKind::Spot {
                cos_inner,
                cos_outer,
            } => (KIND_SPOT, cos_inner, cos_outer),
            SampleKind::Directional { extent } => (KIND_DIRECTIONAL, extent, 0.0),
            SampleKind::PointCone { tan_half } => (KIND_POINT_CONE, tan_half, 0.0),
        };
        let window = super::shadow::Window::of(l, lit, shadow_size)
            .map_or([0.0; 4], |w| [w.centre.x, w.centre.y, w.scale.x, w.scale.y]);
        GpuEmitterSample {
            pos: l.position.extend(kind).to_array(),
            normal: l.normal.extend(a).to_array(),
            radiance: l.radiance.extend(b).to_array(),
            window,
        }
    }
}

pub(crate) const PASS: Pass = Pass {
    name: "direct",
    wgsl: include_str!("../../shaders/direct.wgsl"),
    groups: &[Group {
        stages: wgpu::ShaderStages::COMPUTE,
        bindings: &[
            params("P", &FrameConstants::LAYOUT),
            read("tris", Elem::Struct(&Tri::LAYOUT)),
            read("lights", Elem::Struct(&GpuEmitterSample::LAYOUT)),
            texture("shadows", wgpu::TextureViewDimension::D2Array),
            texture("gbuf", wgpu::TextureViewDimension::D2),
            read_write("direct", Elem::Plain(16)),
            read("surface", Elem::Struct(&Surface::LAYOUT)),
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
        (gbuf, surface): (&wgpu::TextureView, &wgpu::Buffer),
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
                ("surface", surface.as_entire_binding()),
                ("direct", output.as_entire_binding()),
            ],
        );
        Direct { pass, output }
    }

    pub fn encode(&self, enc: &mut wgpu::CommandEncoder, width: u32, height: u32) {
        self.pass.encode(enc, width, height);
    }
}
