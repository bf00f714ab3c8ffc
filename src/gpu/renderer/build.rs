//! What a renderer is built from: the checks of its sizes against the adapter, the buffers
//! its passes share, the passes of the graph, and the read-back buffers.

use super::super::bindings::bytes;
use super::super::common::{FrameConstants, GpuEmitterSample, GpuVpl, Tri};
use super::super::gbuffer::Vertex;
use super::super::{
    check_size, compose::Compose, direct::Direct, downsample::Downsample, gather::Gather,
    gbuffer::GBuffer, interleave::Interleave, ism, shadow::ShadowMaps, temporal::Temporal, Gpu,
};
use super::{RendererConfig, Staging};
use crate::scene::Frame;
use anyhow::{bail, Result};
use glam::Vec3;

/// The checks that must pass before anything renders: sizes against the adapter's limits.
pub fn check_config(c: &RendererConfig, limits: &wgpu::Limits) -> Result<()> {
    if c.slots == 0 || c.slots > 65535 {
        bail!("`vpls` {} is out of range (1 to 65535)", c.slots);
    }
    if !c.ism_size.is_power_of_two() || !(8..=1024).contains(&c.ism_size) {
        bail!(
            "`ism_size` {} must be a power of two from 8 to 1024",
            c.ism_size
        );
    }
    if c.ism_points == 0 || c.ism_points > c.num_points {
        bail!(
            "`ism_points` {} must be 1 to the point-set size {}",
            c.ism_points,
            c.num_points
        );
    }
    if !(1..=8).contains(&c.interleave) {
        bail!("`interleave` {} is out of range (1 to 8)", c.interleave);
    }
    let pyramid = ism::atlas_bytes(c.slots, c.ism_size) * 4 / 3 + 64;
    check_size(
        limits,
        &format!("the ISM atlas for {} VPLs at {}^2", c.slots, c.ism_size),
        pyramid,
        "lower `vpls` or `ism_size`",
    )?;
    if c.light_samples == 0 || c.light_samples * 5 > limits.max_texture_array_layers {
        bail!(
            "`light_samples` {} is out of range (1 to {} on this adapter: 5 shadow faces each)",
            c.light_samples,
            limits.max_texture_array_layers / 5
        );
    }
    if !(1..=8).contains(&c.aa) {
        bail!("`aa` {} is out of range (1 to 8)", c.aa);
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
    // Supersampled, the G-buffer and every per-pixel buffer before `downsample` hold aa^2
    // sub-samples per pixel.
    let (gw, gh) = (c.width as u64 * c.aa as u64, c.height as u64 * c.aa as u64);
    if gw > max2d as u64 || gh > max2d as u64 {
        bail!(
            "`aa` {} at {}x{} needs a {gw}x{gh} G-buffer but the adapter's textures allow {max2d}: lower `aa` or `size`",
            c.aa,
            c.width,
            c.height
        );
    }
    check_size(
        limits,
        &format!("the HDR frame of {gw}x{gh} sub-samples (`aa` {})", c.aa),
        bytes::<[f32; 4]>(gw * gh),
        "lower `size` or `aa`",
    )?;
    Ok(())
}

/// The buffers the passes share, sized for the scene and the settings.
pub(super) struct Shared {
    pub(super) params: wgpu::Buffer,
    pub(super) tris: wgpu::Buffer,
    pub(super) vertices: wgpu::Buffer,
    pub(super) vpls: wgpu::Buffer,
    pub(super) lights: wgpu::Buffer,
    /// The ISM point set followed by the slots' near-field points.
    pub(super) points: wgpu::Buffer,
    pub(super) offsets: Vec<u32>,
    pub(super) slots: wgpu::Buffer,
    pub(super) near_dirs: Vec<Vec3>,
}

impl Shared {
    pub(super) fn new(gpu: &Gpu, c: &RendererConfig, points_frame: &Frame) -> Result<Shared> {
        let tri_count = points_frame.tris.len();
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let params = gpu.buffer(
            "params",
            std::mem::size_of::<FrameConstants>() as u64,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        let tris = gpu.buffer("tris", bytes::<Tri>(tri_count as u64), storage);
        check_size(
            &gpu.limits,
            "the scene's triangles",
            bytes::<Tri>(tri_count as u64),
            "use a smaller scene",
        )?;
        let vertices = gpu.buffer(
            "vertices",
            bytes::<Vertex>(tri_count as u64 * 3),
            wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        );
        let vpls = gpu.buffer("vpls", bytes::<GpuVpl>(c.slots as u64), storage);
        let lights = gpu.buffer(
            "lights",
            bytes::<GpuEmitterSample>(c.light_samples as u64),
            storage,
        );
        let points = ism::point_set(points_frame, c.num_points as usize, c.seed);
        // The point set, then room for every slot's near-field points.
        let near_dirs = ism::near_directions(ism::near_grid(c.ism_size, c.pull_levels));
        let points_len = points.len() as u64 + c.slots as u64 * near_dirs.len() as u64;
        check_size(
            &gpu.limits,
            "the ISM points",
            bytes::<ism::Point>(points_len),
            "lower `vpls` or `ism_points`",
        )?;
        let points_buf = gpu.buffer("ism points", bytes::<ism::Point>(points_len), storage);
        gpu.queue
            .write_buffer(&points_buf, 0, bytemuck::cast_slice(&points));
        let offsets: Vec<u32> = (0..c.slots)
            .map(|s| ism::slot_offset(c.seed, s, c.num_points))
            .collect();
        let slots = gpu.buffer(
            "ism slots to redraw",
            bytes::<[u32; 2]>(c.slots as u64),
            storage,
        );
        Ok(Shared {
            params,
            tris,
            vertices,
            vpls,
            lights,
            points: points_buf,
            offsets,
            slots,
            near_dirs,
        })
    }
}

/// The passes of [`GRAPH`], built over the shared buffers.
pub(super) struct Passes {
    pub(super) gbuffer: GBuffer,
    pub(super) surface: Option<super::super::surface::SurfacePass>,
    pub(super) shadows: ShadowMaps,
    pub(super) direct: Direct,
    pub(super) ism: ism::Ism,
    pub(super) gather: Gather,
    pub(super) interleave: Option<Interleave>,
    pub(super) temporal: Option<Temporal>,
    pub(super) compose: Compose,
    pub(super) downsample: Option<Downsample>,
}

impl Passes {
    pub(super) fn new(
        gpu: &Gpu,
        c: &RendererConfig,
        points_frame: &Frame,
        b: &Shared,
    ) -> Result<Passes> {
        // Every pass before `downsample` runs on the sub-sample grid.
        let (gw, gh) = c.grid();
        let pixels = gw as u64 * gh as u64;
        let out_pixels = c.width as u64 * c.height as u64;
        let texture_data = super::super::surface::TextureData::new(gpu, points_frame)?;
        let gbuffer = GBuffer::new(gpu, (c.width, c.height, c.aa), &texture_data, &b.tris);
        let surface_buf = gpu.buffer(
            "surface",
            bytes::<super::super::common::Surface>(pixels),
            wgpu::BufferUsages::STORAGE,
        );
        let surface = super::super::surface::SurfacePass::new(
            gpu,
            &texture_data,
            &b.params,
            &b.tris,
            (&gbuffer.view, &surface_buf),
        );
        let shadows = ShadowMaps::new(
            gpu,
            (c.shadow_size, c.light_samples),
            // Cut-outs and open single-sided triangles need each fragment's triangle.
            (
                points_frame.tris.len() as u32,
                points_frame.has_cutouts()
                    || points_frame
                        .sides()
                        .is_some_and(|s| s.contains(&crate::scene::Sides::OPEN)),
            ),
            &texture_data,
            &b.tris,
        );
        let direct = Direct::new(
            gpu,
            &b.params,
            &b.tris,
            &b.lights,
            &shadows.array_view,
            (&gbuffer.view, &surface_buf),
            pixels,
        );
        let ism = ism::Ism::new(
            gpu,
            &b.params,
            &b.tris,
            &b.points,
            &b.vpls,
            &b.slots,
            c.slots,
            c.ism_size,
            c.pull_levels,
        );
        let gather = Gather::new(
            gpu,
            &b.params,
            &b.tris,
            &b.vpls,
            &ism.pyramid,
            (&gbuffer.view, &surface_buf),
            pixels,
        );
        let interleave = (c.interleave > 1).then(|| {
            Interleave::new(
                gpu,
                &b.params,
                &b.tris,
                (&gbuffer.view, &surface_buf),
                &gather.output,
                pixels,
            )
        });
        let indirect = interleave.as_ref().map_or(&gather.output, |f| &f.output);
        // The pixels' samples are tile 0's: rows 0..height of the grid.
        let tile0 = gw as u64 * c.height as u64;
        if c.accumulate > 1 {
            check_size(
                &gpu.limits,
                &format!("the history of {gw}x{} samples (`accumulate`)", c.height),
                bytes::<super::super::temporal::HistorySample>(tile0),
                "lower `size` or `aa`, or drop `accumulate`",
            )?;
        }
        let temporal = (c.accumulate > 1).then(|| {
            Temporal::new(
                gpu,
                &b.params,
                &b.tris,
                &gbuffer.view,
                indirect,
                tile0,
                c.accumulate,
            )
        });
        let indirect = temporal.as_ref().map_or(indirect, |t| &t.output);
        let compose = Compose::new(
            gpu,
            &b.params,
            &b.tris,
            (&gbuffer.view, &surface_buf),
            (&direct.output, indirect),
            pixels,
            c.aa > 1,
        );
        let downsample = (c.aa > 1).then(|| {
            Downsample::new(
                gpu,
                &b.params,
                (&compose.hdr, &direct.output, &compose.indirect_ss),
                out_pixels,
            )
        });
        Ok(Passes {
            gbuffer,
            surface,
            shadows,
            direct,
            ism,
            gather,
            interleave,
            temporal,
            compose,
            downsample,
        })
    }
}

impl Staging {
    pub(super) fn new(gpu: &Gpu, pixels: u64) -> Staging {
        let read = wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST;
        Staging {
            hdr: gpu.buffer("hdr readback", bytes::<[f32; 4]>(pixels), read),
            ldr: gpu.buffer("ldr readback", bytes::<u32>(pixels), read),
            direct: gpu.buffer("direct readback", bytes::<[f32; 4]>(pixels), read),
            indirect: gpu.buffer("indirect readback", bytes::<[f32; 4]>(pixels), read),
        }
    }
}
