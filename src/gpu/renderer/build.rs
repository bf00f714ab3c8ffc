//! What a renderer is built from: the checks of its sizes against the adapter, the buffers
//! its passes share, the passes of the graph, and the read-back buffers.

use super::super::bindings::bytes;
use super::super::common::{FrameConstants, GpuEmitterSample, GpuVpl, Tri};
use super::super::gbuffer::Vertex;
use super::super::surface::TextureData;
use super::super::{check_size, ism, Gpu};
use super::pass::FramePass;
use super::{RendererConfig, Staging};
use crate::scene::Frame;
use anyhow::{anyhow, bail, Result};
use glam::Vec3;
use std::collections::HashMap;

/// The most bytes irad asks the adapter for in one texture (the shadow maps' array, the
/// largest). wgpu reports no memory size, and an allocation past what the device holds fails
/// late, as a device error after the output folder was made; 4 GiB is a cap most discrete
/// GPUs hold and one the settings users need stay far below (the default shadow maps for 64
/// samples take 84 MiB).
pub const MAX_TEXTURE_BYTES: u64 = 4 << 30;

/// The bytes of the shadow maps for `samples` emitter samples at `size`^2: 5 faces each, 4
/// bytes a texel, and one depth buffer.
pub fn shadow_bytes(samples: u32, size: u32) -> u64 {
    (samples as u64 * 5 + 1) * (size as u64 * size as u64) * 4
}

/// The shadow maps for `samples` at `size` within [`MAX_TEXTURE_BYTES`].
pub fn check_shadow_maps(samples: u32, size: u32) -> Result<()> {
    let need = shadow_bytes(samples, size);
    if need > MAX_TEXTURE_BYTES {
        bail!(
            "the shadow maps for `light_samples` {samples} at `shadow_size` {size} need {:.1} GiB ({samples} x 5 faces of {size}^2 texels, 4 bytes each), more than irad's cap of {} GiB for one texture: lower `shadow_size` or `light_samples`",
            need as f64 / (1u64 << 30) as f64,
            MAX_TEXTURE_BYTES >> 30
        );
    }
    Ok(())
}

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
    check_shadow_maps(c.light_samples, c.shadow_size)?;
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

/// What the passes of [`GRAPH`](super::graph::GRAPH) are built from: the adapter, the
/// settings, the frame that sizes them, the shared buffers, and the named resources the passes
/// built before wrote (`gbuffer`, `surface`, `indirect`, ...). A pass reads a resource by the
/// name its graph entry declares in `reads` and writes it by a name declared in `writes`
/// (its own, or those of the passes after it that share its GPU state, as `ism_pullpush`
/// shares `ism_splat`'s); the builder refuses any other, so the declarations are the code's.
pub(crate) struct Builder<'a> {
    pub(crate) gpu: &'a Gpu,
    pub(crate) c: &'a RendererConfig,
    pub(crate) frame: &'a Frame,
    pub(crate) shared: &'a Shared,
    pub(crate) textures: TextureData,
    buffers: HashMap<&'static str, wgpu::Buffer>,
    views: HashMap<&'static str, wgpu::TextureView>,
    /// The graph entries whose declarations the pass being built may use.
    current: &'static [FramePass],
}

impl<'a> Builder<'a> {
    pub(super) fn new(
        gpu: &'a Gpu,
        c: &'a RendererConfig,
        frame: &'a Frame,
        shared: &'a Shared,
    ) -> Result<Self> {
        Ok(Builder {
            gpu,
            c,
            frame,
            shared,
            textures: TextureData::new(gpu, frame)?,
            buffers: HashMap::new(),
            views: HashMap::new(),
            current: &[],
        })
    }

    /// The next pass built declares its reads and writes in `entries`.
    pub(super) fn enter(&mut self, entries: &'static [FramePass]) {
        self.current = entries;
    }

    fn declared(&self, name: &str, what: &str) -> Result<()> {
        declared(self.current, name, what)
    }

    /// The buffer `name`, as the last pass that wrote it left it.
    pub(crate) fn buffer(&self, name: &str) -> Result<&wgpu::Buffer> {
        self.declared(name, "reads")?;
        self.buffers
            .get(name)
            .ok_or_else(|| anyhow!("the renderer's graph reads `{name}` before a pass writes it"))
    }

    /// The texture view `name`, as the last pass that wrote it left it.
    pub(crate) fn view(&self, name: &str) -> Result<&wgpu::TextureView> {
        self.declared(name, "reads")?;
        self.views
            .get(name)
            .ok_or_else(|| anyhow!("the renderer's graph reads `{name}` before a pass writes it"))
    }

    /// The pass being built writes `buffer` as `name` (later passes read it by that name).
    pub(crate) fn write(&mut self, name: &'static str, buffer: &wgpu::Buffer) -> Result<()> {
        self.declared(name, "writes")?;
        self.buffers.insert(name, buffer.clone());
        Ok(())
    }

    /// The pass being built writes `view` as `name`.
    pub(crate) fn write_view(
        &mut self,
        name: &'static str,
        view: &wgpu::TextureView,
    ) -> Result<()> {
        self.declared(name, "writes")?;
        self.views.insert(name, view.clone());
        Ok(())
    }

    /// Samples on the sub-sample grid (what every pass before `downsample` runs on).
    pub(crate) fn grid_pixels(&self) -> u64 {
        let (gw, gh) = self.c.grid();
        gw as u64 * gh as u64
    }

    /// What the graph leaves in `hdr`, `ldr`, `direct` and `indirect`: the buffers read back.
    pub(super) fn outputs(&self) -> Result<Outputs> {
        let get = |name: &str| {
            self.buffers
                .get(name)
                .cloned()
                .ok_or_else(|| anyhow!("the renderer's graph never writes `{name}`"))
        };
        Ok(Outputs {
            hdr: get("hdr")?,
            ldr: get("ldr")?,
            direct: get("direct")?,
            indirect: get("indirect")?,
        })
    }
}

/// Whether the pass whose graph entries are `current` (the pass, then those after it that use
/// its GPU state) declares `name` in `what` (`reads`: the pass's own; `writes`: any of them).
pub(super) fn declared(current: &[FramePass], name: &str, what: &str) -> Result<()> {
    let ok = match what {
        "reads" => current.first().is_some_and(|p| p.reads.contains(&name)),
        _ => current.iter().any(|p| p.writes.contains(&name)),
    };
    if !ok {
        let pass = current.first().map_or("?", |p| p.name);
        bail!("the renderer's pass `{pass}` uses `{name}`, which its graph entry does not list in `{what}`");
    }
    Ok(())
}

/// The frame's outputs at the output size, as the last passes that wrote them left them.
pub(super) struct Outputs {
    pub(super) hdr: wgpu::Buffer,
    pub(super) ldr: wgpu::Buffer,
    pub(super) direct: wgpu::Buffer,
    pub(super) indirect: wgpu::Buffer,
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
