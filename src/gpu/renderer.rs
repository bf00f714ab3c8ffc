//! The GPU frame: uploads the frame's triangles, VPLs and emitter samples, runs the passes in
//! order (G-buffer, shadow hemicubes, direct light, ISM splat, pull-push, gather, compose) and
//! reads the frame back. Each pass is its own submission, timed to its completion.

use super::{
    check_size, compose::Compose, direct::Direct, gather::Gather, gbuffer::GBuffer, ism,
    shadow::ShadowMaps, Gpu,
};
use crate::image::Hdr;
use crate::scene::{EmitterSample, Frame};
use crate::vpl::ShadedVpl;
use anyhow::{bail, Result};
use glam::Vec3;
use std::time::Instant;

/// Sizes and quality settings of the GPU renderer.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RendererConfig {
    pub width: u32,
    pub height: u32,
    /// VPL slots (atlas tiles).
    pub max_vpls: u32,
    /// ISM tile side in texels.
    pub ism_size: u32,
    /// Points each VPL slot splats.
    pub points_per_vpl: u32,
    /// Points in the scene's point set.
    pub num_points: u32,
    /// Pull-push levels (holes up to 2^levels texels are filled).
    pub pull_levels: u32,
    /// ISM depth bias, in texel footprints.
    pub ism_bias: f32,
    /// Emitter samples for direct light.
    pub light_samples: u32,
    /// Shadow hemicube face side in texels.
    pub shadow_size: u32,
    /// Shadow depth bias, in texel footprints.
    pub shadow_bias: f32,
    pub exposure: f32,
    /// Seeds the point set and the slots' subsets.
    pub seed: u64,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    width: u32,
    height: u32,
    num_vpls: u32,
    ism_size: u32,
    points_per_vpl: u32,
    num_points: u32,
    num_light_samples: u32,
    shadow_size: u32,
    far: f32,
    dmin: f32,
    exposure: f32,
    ism_bias: f32,
    cam_pos: [f32; 4],
    shadow_bias: f32,
    near: f32,
    pull_levels: u32,
    pad: u32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuTri {
    v: [[f32; 4]; 3],
    n: [f32; 4],
    albedo: [f32; 4],
    emission: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Vec4x3([[f32; 4]; 3]);

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Vertex {
    pos: [f32; 3],
    tri: u32,
}

/// What one GPU frame needs besides the renderer's fixed state.
pub struct GpuFrame<'a> {
    pub frame: &'a Frame,
    /// VPL i occupies slot i (and splats slot i's point subset).
    pub vpls: &'a [ShadedVpl],
    pub lights: &'a [EmitterSample],
    /// Distance clamp of the gather (`--clamp`).
    pub dmin: f32,
}

/// A frame's rendered image: linear HDR, the 8-bit preview, optionally its components, and
/// timings.
pub struct RenderedImage {
    pub hdr: Hdr,
    pub ldr: Vec<u8>,
    pub direct: Option<Hdr>,
    pub indirect: Option<Hdr>,
    /// Seconds per stage, in order.
    pub timings: Vec<(&'static str, f64)>,
}

pub struct Renderer {
    pub gpu: std::sync::Arc<Gpu>,
    pub config: RendererConfig,
    tri_count: usize,
    params: wgpu::Buffer,
    tris: wgpu::Buffer,
    vertices: wgpu::Buffer,
    vpls: wgpu::Buffer,
    lights: wgpu::Buffer,
    gbuffer: GBuffer,
    shadows: ShadowMaps,
    direct: Direct,
    ism: ism::Ism,
    gather: Gather,
    compose: Compose,
}

/// The checks that must pass before anything renders: sizes against the adapter's limits.
pub fn check_config(c: &RendererConfig, limits: &wgpu::Limits) -> Result<()> {
    if c.max_vpls == 0 || c.max_vpls > 65535 {
        bail!("--vpls {} is out of range (1 to 65535)", c.max_vpls);
    }
    if !c.ism_size.is_power_of_two() || !(8..=1024).contains(&c.ism_size) {
        bail!(
            "--ism-size {} must be a power of two from 8 to 1024",
            c.ism_size
        );
    }
    if c.points_per_vpl == 0 || c.points_per_vpl > c.num_points {
        bail!(
            "--ism-points {} must be 1 to the point-set size {}",
            c.points_per_vpl,
            c.num_points
        );
    }
    let pyramid = ism::atlas_bytes(c.max_vpls, c.ism_size) * 4 / 3 + 64;
    check_size(
        limits,
        &format!("the ISM atlas for {} VPLs at {}^2", c.max_vpls, c.ism_size),
        pyramid,
        "lower --vpls or --ism-size",
    )?;
    if c.light_samples == 0 || c.light_samples * 5 > limits.max_texture_array_layers {
        bail!(
            "--light-samples {} is out of range (1 to {} on this adapter: 5 shadow faces each)",
            c.light_samples,
            limits.max_texture_array_layers / 5
        );
    }
    let max2d = limits.max_texture_dimension_2d;
    if c.width > max2d || c.height > max2d || c.shadow_size > max2d || c.shadow_size < 8 {
        bail!(
            "image {}x{} or shadow size {} exceeds the adapter's textures ({max2d})",
            c.width,
            c.height,
            c.shadow_size
        );
    }
    check_size(
        limits,
        "the HDR frame",
        c.width as u64 * c.height as u64 * 16,
        "lower --size",
    )?;
    Ok(())
}

impl Renderer {
    /// Builds every pass for frames of `tri_count` triangles; `points_frame` places the ISM
    /// point set (by area) once.
    pub fn new(
        gpu: std::sync::Arc<Gpu>,
        config: RendererConfig,
        points_frame: &Frame,
    ) -> Result<Renderer> {
        check_config(&config, &gpu.limits)?;
        let c = &config;
        let tri_count = points_frame.tris.len();
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let params = gpu.buffer(
            "params",
            std::mem::size_of::<Params>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let tris = gpu.buffer("tris", tri_count as u64 * 96, storage);
        check_size(
            &gpu.limits,
            "the scene's triangles",
            tri_count as u64 * 96,
            "use a smaller scene",
        )?;
        let vertices = gpu.buffer(
            "vertices",
            tri_count as u64 * 48,
            wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        );
        let vpls = gpu.buffer("vpls", c.max_vpls as u64 * 48, storage);
        let lights = gpu.buffer("lights", c.light_samples as u64 * 48, storage);
        let points = ism::point_set(points_frame, c.num_points as usize, c.seed);
        let points_buf = gpu.buffer("ism points", points.len() as u64 * 16, storage);
        gpu.queue
            .write_buffer(&points_buf, 0, bytemuck::cast_slice(&points));
        let offsets: Vec<u32> = (0..c.max_vpls)
            .map(|s| ism::slot_offset(c.seed, s, c.num_points))
            .collect();
        let offsets_buf = gpu.buffer("ism slot offsets", offsets.len() as u64 * 4, storage);
        gpu.queue
            .write_buffer(&offsets_buf, 0, bytemuck::cast_slice(&offsets));
        let pixels = c.width as u64 * c.height as u64;
        let gbuffer = GBuffer::new(&gpu, c.width, c.height);
        let shadows = ShadowMaps::new(&gpu, c.shadow_size, c.light_samples);
        let direct = Direct::new(
            &gpu,
            &params,
            &tris,
            &lights,
            &shadows.array_view,
            &gbuffer.view,
            pixels,
        );
        let ism = ism::Ism::new(
            &gpu,
            &params,
            &tris,
            &points_buf,
            &vpls,
            &offsets_buf,
            c.max_vpls,
            c.ism_size,
            c.pull_levels,
        );
        let gather = Gather::new(
            &gpu,
            &params,
            &tris,
            &vpls,
            &ism.pyramid,
            &gbuffer.view,
            pixels,
        );
        let compose = Compose::new(
            &gpu,
            &params,
            &tris,
            &gbuffer.view,
            &direct.output,
            &gather.output,
            pixels,
        );
        Ok(Renderer {
            gpu,
            config,
            tri_count,
            params,
            tris,
            vertices,
            vpls,
            lights,
            gbuffer,
            shadows,
            direct,
            ism,
            gather,
            compose,
        })
    }

    fn upload(&self, input: &GpuFrame, far: f32, near: f32) -> Result<()> {
        let f = input.frame;
        let c = &self.config;
        if f.tris.len() != self.tri_count {
            bail!(
                "the frame has {} triangles but the renderer was built for {}",
                f.tris.len(),
                self.tri_count
            );
        }
        if input.vpls.len() > c.max_vpls as usize || input.lights.len() > c.light_samples as usize {
            bail!(
                "{} VPLs / {} light samples exceed the renderer's {} / {}",
                input.vpls.len(),
                input.lights.len(),
                c.max_vpls,
                c.light_samples
            );
        }
        let params = Params {
            width: c.width,
            height: c.height,
            num_vpls: input.vpls.len() as u32,
            ism_size: c.ism_size,
            points_per_vpl: c.points_per_vpl,
            num_points: c.num_points,
            num_light_samples: input.lights.len() as u32,
            shadow_size: c.shadow_size,
            far,
            dmin: input.dmin,
            exposure: c.exposure,
            ism_bias: c.ism_bias,
            cam_pos: f.camera.position.extend(1.0).to_array(),
            shadow_bias: c.shadow_bias,
            near,
            pull_levels: c.pull_levels,
            pad: 0,
        };
        let q = &self.gpu.queue;
        q.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let tris: Vec<GpuTri> = (0..f.tris.len())
            .map(|i| GpuTri {
                v: f.tris[i].map(|p| p.extend(1.0).to_array()),
                n: f.normals[i].extend(0.0).to_array(),
                albedo: f.albedo(i).extend(0.0).to_array(),
                emission: f.emission(i).extend(0.0).to_array(),
            })
            .collect();
        q.write_buffer(&self.tris, 0, bytemuck::cast_slice(&tris));
        let verts: Vec<Vertex> = f
            .tris
            .iter()
            .enumerate()
            .flat_map(|(i, t)| {
                t.map(|p| Vertex {
                    pos: p.to_array(),
                    tri: i as u32,
                })
            })
            .collect();
        q.write_buffer(&self.vertices, 0, bytemuck::cast_slice(&verts));
        let v4 = |v: Vec3| v.extend(0.0).to_array();
        let vpls: Vec<Vec4x3> = input
            .vpls
            .iter()
            .map(|v| Vec4x3([v4(v.position), v4(v.normal), v4(v.flux)]))
            .collect();
        if !vpls.is_empty() {
            q.write_buffer(&self.vpls, 0, bytemuck::cast_slice(&vpls));
        }
        let lights: Vec<Vec4x3> = input
            .lights
            .iter()
            .map(|l| Vec4x3([v4(l.position), v4(l.normal), v4(l.radiance)]))
            .collect();
        if !lights.is_empty() {
            q.write_buffer(&self.lights, 0, bytemuck::cast_slice(&lights));
        }
        Ok(())
    }

    /// Renders one frame. With `components`, the direct and indirect images come back too.
    pub fn render(&mut self, input: &GpuFrame, components: bool) -> Result<RenderedImage> {
        let f = input.frame;
        let c = self.config.clone();
        let (lo, hi) = f.bounds();
        let far = (hi - lo)
            .length()
            .max((f.camera.position - (lo + hi) * 0.5).length() * 2.0)
            * 1.5;
        let near = far * 1e-5;
        let mut timings = Vec::new();
        let mut t0 = Instant::now();
        let mut stage =
            |name: &'static str, gpu: &Gpu, enc: Option<wgpu::CommandEncoder>| -> Result<()> {
                if let Some(enc) = enc {
                    gpu.queue.submit([enc.finish()]);
                }
                gpu.wait()?;
                let now = Instant::now();
                timings.push((name, (now - t0).as_secs_f64()));
                t0 = now;
                Ok(())
            };
        let encoder = |gpu: &Gpu| gpu.device.create_command_encoder(&Default::default());
        self.upload(input, far, near)?;
        stage("upload", &self.gpu, None)?;
        let count = (self.tri_count * 3) as u32;

        let mut enc = encoder(&self.gpu);
        let view_proj =
            f.camera.projection(c.width, c.height, near.max(1e-3), far) * f.camera.view();
        self.gbuffer
            .encode(&self.gpu, &mut enc, &self.vertices, count, view_proj);
        stage("gbuffer", &self.gpu, Some(enc))?;

        let mut enc = encoder(&self.gpu);
        let samples: Vec<(Vec3, Vec3)> = input
            .lights
            .iter()
            .map(|l| (l.position, l.normal))
            .collect();
        self.shadows.encode(
            &self.gpu,
            &mut enc,
            &samples,
            near,
            far,
            &self.vertices,
            count,
        );
        stage("shadow_maps", &self.gpu, Some(enc))?;

        let mut enc = encoder(&self.gpu);
        self.direct.encode(&mut enc, c.width, c.height);
        stage("direct", &self.gpu, Some(enc))?;

        let n = input.vpls.len() as u32;
        let mut enc = encoder(&self.gpu);
        self.ism.encode_splat(&mut enc, n, c.points_per_vpl);
        stage("ism_splat", &self.gpu, Some(enc))?;

        let mut enc = encoder(&self.gpu);
        if n > 0 {
            self.ism.encode_pull_push(&mut enc, n);
        }
        stage("ism_pullpush", &self.gpu, Some(enc))?;

        let mut enc = encoder(&self.gpu);
        self.gather.encode(&mut enc, c.width, c.height);
        stage("gather", &self.gpu, Some(enc))?;

        let mut enc = encoder(&self.gpu);
        self.compose.encode(&mut enc, c.width, c.height);
        stage("compose", &self.gpu, Some(enc))?;

        let pixels = c.width as u64 * c.height as u64;
        let read_hdr = |buf: &wgpu::Buffer| -> Result<Hdr> {
            let bytes = self.gpu.read_buffer(buf, pixels * 16)?;
            let v: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
            Ok(Hdr {
                width: c.width,
                height: c.height,
                data: v.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect(),
            })
        };
        let hdr = read_hdr(&self.compose.hdr)?;
        let ldr: Vec<u8> = self
            .gpu
            .read_buffer(&self.compose.ldr, pixels * 4)?
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        let (direct, indirect) = if components {
            (
                Some(read_hdr(&self.direct.output)?),
                Some(read_hdr(&self.gather.output)?),
            )
        } else {
            (None, None)
        };
        stage("readback", &self.gpu, None)?;
        Ok(RenderedImage {
            hdr,
            ldr,
            direct,
            indirect,
            timings,
        })
    }
}
