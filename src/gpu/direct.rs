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

/// The depth bias of an environment sample's orthographic map, as a fraction of a directional
/// light's (`radiance.w` of its sample; 0 stands for 1). Light from every direction grazes
/// some walls, and an interior lit through an opening leaks where the full bias lets a wall's
/// shadow through: on `cornell-box` under the sky the direct light is 3.7% above its CPU twin's
/// with the full bias, 1.2% with half, while the open test model stays within 0.1% (no acne;
/// `examples/env_split.rs`).
pub const ENV_BIAS: f32 = 0.5;

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
            // Drawn as a directional light, with half its depth bias (`ENV_BIAS`).
            SampleKind::Environment { extent } => (KIND_DIRECTIONAL, extent, ENV_BIAS),
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
            read("env", Elem::Plain(16)),
        ],
    }],
};

/// The `env` buffer's header: vec4s before the texels (see [`EnvironmentBuffer`]).
const ENV_HEADER: u64 = 8;
/// The most texels of the environment the background reads (a larger map is averaged down
/// by 2 until it fits: only what the camera sees of it, never its light, is coarser).
pub const MAX_ENV_TEXELS: usize = 1 << 22;

/// The environment as the direct pass draws it where the camera sees no geometry
/// (`shaders/direct.wgsl`): vec4 0 = (width, height, 1 if there is one, 0), vec4s 1-4 the
/// columns of the inverse of the camera's view-projection (written each frame), then the
/// map's texels, row 0 at the top. The environment's light comes through the emitter samples
/// ([`crate::scene::SampleKind::Environment`]).
struct EnvironmentBuffer {
    buffer: wgpu::Buffer,
    on: bool,
}

impl EnvironmentBuffer {
    fn new(gpu: &Gpu, frame: &crate::scene::Frame) -> Self {
        let env = frame.emitters.environment.as_deref();
        let (w, h, texels) = match env {
            Some(e) => fit(e.width, e.height, e.texels.clone()),
            None => (1, 1, vec![glam::Vec3::ZERO]),
        };
        let mut data: Vec<[f32; 4]> = vec![[0.0; 4]; ENV_HEADER as usize];
        data[0] = [w as f32, h as f32, env.is_some() as u32 as f32, 0.0];
        data.extend(texels.iter().map(|t| t.extend(0.0).to_array()));
        let buffer = gpu.buffer(
            "environment",
            super::bindings::bytes::<[f32; 4]>(data.len() as u64),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        gpu.queue
            .write_buffer(&buffer, 0, bytemuck::cast_slice(&data));
        EnvironmentBuffer {
            buffer,
            on: env.is_some(),
        }
    }
}

/// A map of at most [`MAX_ENV_TEXELS`] texels: `texels` averaged over 2 x 2 blocks until it
/// fits.
fn fit(mut w: u32, mut h: u32, mut t: Vec<glam::Vec3>) -> (u32, u32, Vec<glam::Vec3>) {
    while (w as usize) * (h as usize) > MAX_ENV_TEXELS && w > 1 && h > 1 {
        let (nw, nh) = (w / 2, h / 2);
        let at = |x: u32, y: u32| t[(y.min(h - 1) * w + x.min(w - 1)) as usize];
        t = (0..nh)
            .flat_map(|y| (0..nw).map(move |x| (x, y)))
            .map(|(x, y)| {
                (at(2 * x, 2 * y)
                    + at(2 * x + 1, 2 * y)
                    + at(2 * x, 2 * y + 1)
                    + at(2 * x + 1, 2 * y + 1))
                    * 0.25
            })
            .collect();
        (w, h) = (nw, nh);
    }
    (w, h, t)
}

pub struct Direct {
    pass: PixelPass,
    pub output: wgpu::Buffer,
    env: EnvironmentBuffer,
}

impl Direct {
    pub fn new(
        gpu: &Gpu,
        params: &wgpu::Buffer,
        tris: &wgpu::Buffer,
        lights: &wgpu::Buffer,
        shadows: &wgpu::TextureView,
        (gbuf, surface): (&wgpu::TextureView, &wgpu::Buffer),
        (pixels, frame): (u64, &crate::scene::Frame),
    ) -> Self {
        let env = EnvironmentBuffer::new(gpu, frame);
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
                ("env", env.buffer.as_entire_binding()),
            ],
        );
        Direct { pass, output, env }
    }

    /// Writes the camera's inverse view-projection for the background (nothing without an
    /// environment).
    pub fn upload_camera(&self, gpu: &Gpu, view_proj: glam::Mat4) {
        if self.env.on {
            let inv = view_proj.inverse().to_cols_array_2d();
            gpu.queue
                .write_buffer(&self.env.buffer, 16, bytemuck::cast_slice(&inv));
        }
    }

    pub fn encode(&self, enc: &mut wgpu::CommandEncoder, width: u32, height: u32) {
        self.pass.encode(enc, width, height);
    }
}
