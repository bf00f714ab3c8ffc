//! The GPU frame: uploads the frame's triangles, VPLs and emitter samples, runs the passes in
//! order (G-buffer, shadow hemicubes, direct light, ISM splat, pull-push, gather, interleave
//! filter, compose, and with supersampling the downsample that box-filters sub-samples into
//! pixels) and reads the frame back, all in one submission (or, profiling without timestamp queries,
//! one per pass: see `profile`).

mod build;
pub mod graph;
pub mod pass;

pub use build::{check_config, check_shadow_maps, shadow_bytes, MAX_TEXTURE_BYTES};
use build::{Builder, Outputs, Shared};
use graph::Passes;

use super::bindings::bytes;
use super::common::{FrameConstants, GpuEmitterSample, GpuVpl, Tri};
use super::gbuffer::Vertex;
use super::profile::{has_timestamps, read_mapped, Profiling, Recorder, Timestamps};
use super::temporal::{HistoryMode, HistoryUse};
use super::{ism, Gpu};
use crate::image::Hdr;
use crate::scene::{EmitterSample, Frame};
use crate::vpl::ShadedVpl;
use anyhow::{bail, Result};
use glam::Vec3;
use graph::GRAPH;
use std::time::Instant;

/// Sizes and quality settings of the GPU renderer.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RendererConfig {
    pub width: u32,
    pub height: u32,
    /// VPL slots (atlas tiles).
    pub slots: u32,
    /// ISM tile side in texels.
    pub ism_size: u32,
    /// Points each VPL slot splats.
    pub ism_points: u32,
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
    /// Interleaved gather block side (1: every pixel gathers every VPL; see `interleave`),
    /// in sub-samples.
    pub interleave: u32,
    /// Supersampling: the passes run on `aa x aa` sub-samples per pixel and `downsample`
    /// box-filters them into pixels (1: one sample at each pixel centre).
    pub aa: u32,
    /// Supersampled, whether the sub-samples of a pixel split the emitter samples among them
    /// (each sums `1 / aa^2` of them: one sample's work a pixel) or each sums them all
    /// (`aa^2` times the direct pass's work). Split for instant radiosity, whose flicker is
    /// the VPLs'; not for a classical method, whose view-independent solution otherwise
    /// shows the split as flicker in the penumbrae (docs/radiosity.md, "Edges that hold
    /// still").
    pub split_light_samples: bool,
    /// Camera rays per side for the pixels at emitters' edges (`trace::edges`; 0: off).
    pub edge_rays: u32,
    /// Rays a pixel for the clamping-bias compensation (`compensation`; 0: off).
    pub compensate: u32,
    /// Temporal accumulation: the indirect light averages up to this many frames while the
    /// light is the same (`temporal`; 0 or 1: off).
    pub accumulate: u32,
    /// What the history does under a moving light or object (`temporal`).
    pub history: HistoryMode,
    pub exposure: f32,
    /// Seeds the point set and the slots' subsets.
    pub seed: u64,
}

impl RendererConfig {
    /// The sub-sample grid the passes before `downsample` run on: `aa x aa` tiles of the output
    /// size, tile (i, j) sampling every pixel at `gbuffer::subsample(i, j, aa)`.
    pub fn grid(&self) -> (u32, u32) {
        (self.width * self.aa, self.height * self.aa)
    }
}

/// What one GPU frame needs besides the renderer's fixed state.
pub struct GpuFrame<'a> {
    pub frame: &'a Frame,
    /// VPL i occupies slot i (and splats slot i's point subset).
    pub vpls: &'a [ShadedVpl],
    pub emitter_samples: &'a [EmitterSample],
    /// Distance clamp of the gather (`--clamp`).
    pub clamp: f32,
    /// Distance clamp of the emitter triangles' samples in the direct pass (0: none; the
    /// gather's clamp when the clamping-bias compensation adds back what both leave out).
    pub direct_clamp: f32,
    /// The VPLs' near-field points ([`ism::near_points`] over [`Renderer::near_directions`],
    /// in slot order), or none (then the ISMs hold the point set alone).
    pub near: &'a [ism::Point],
    /// The light's relative change since the last frame (`vpl::gradient`), for temporal
    /// accumulation under a moving light or object (none: not measured).
    pub gradient: Option<&'a crate::vpl::gradient::Gradient>,
}

/// A frame's rendered image: linear HDR, the 8-bit preview, optionally its components, and
/// timings.
pub struct RenderedImage {
    pub hdr: Hdr,
    pub ldr: Vec<u8>,
    pub direct: Option<Hdr>,
    pub indirect: Option<Hdr>,
    /// Seconds per stage, in order: `upload` (CPU), the passes of [`PASSES`] (GPU times
    /// with timestamps, wall times when serialized, absent when `Off`), and `readback` (the
    /// rest of the frame's GPU wait: copies, mapping, and with `Off` the passes too).
    pub timings: Vec<(&'static str, f64)>,
    /// How the passes were timed.
    pub profiling: Profiling,
    /// What was kept from the previous frame.
    pub reused: Reuse,
    /// What the raster passes drew.
    pub drawn: Drawn,
}

/// The passes of a frame, in order, as timings name them (from [`GRAPH`]).
pub const PASSES: [&str; GRAPH.len()] = {
    let mut names = [""; GRAPH.len()];
    let mut i = 0;
    while i < GRAPH.len() {
        names[i] = GRAPH[i].name;
        i += 1;
    }
    names
};

/// What a frame reused from the previous one (for run records).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Reuse {
    /// The triangles are the same bits as last frame's: not uploaded.
    pub geometry_kept: bool,
    /// The emitter samples are the same: not uploaded.
    pub lights_kept: bool,
    /// Whether the VPLs were uploaded (any bit of any VPL changed).
    pub vpls_uploaded: bool,
    /// The shadow hemicubes were kept (same samples, same geometry).
    pub shadow_maps_kept: bool,
    /// VPL slots whose ISM tile was kept (same VPL position and normal, same geometry).
    pub ism_tiles_kept: u32,
    /// VPL slots whose ISM tile was splatted and pulled/pushed again.
    pub ism_tiles_drawn: u32,
    /// With `--accumulate`: the indirect light averaged the last frame's history (as it was
    /// with the same triangles and emitter samples, after the change test without; else it
    /// started anew).
    pub history_kept: bool,
    /// The history went through the change test (the light or the objects moved).
    pub history_tested: bool,
}

/// What the raster passes drew of the frame's triangles, after leaving out what each view
/// cannot see (`scene::culling`; for run records).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Drawn {
    /// The frame's triangles.
    pub triangles: u64,
    /// Triangles the G-buffer drew (in each sub-sample tile), and of them those drawn front
    /// faces only.
    pub gbuffer_triangles: u64,
    pub gbuffer_front_only: u64,
    /// Shadow faces drawn this frame (none when the maps were kept), the triangles they drew
    /// together, and of them those drawn front faces only.
    pub shadow_faces: u64,
    pub shadow_triangles: u64,
    pub shadow_front_only: u64,
}

/// What the last frame uploaded, to tell what changed.
#[derive(Default)]
struct Last {
    tris: Vec<Tri>,
    vpls: Vec<GpuVpl>,
    lights: Vec<GpuEmitterSample>,
    /// The box each emitter sample's light can reach ([`super::shadow::lit_boxes`]).
    lit: Vec<(glam::Vec3, glam::Vec3)>,
}

/// Whether two slices hold the same bits.
fn same<T: bytemuck::Pod>(a: &[T], b: &[T]) -> bool {
    bytemuck::cast_slice::<T, u8>(a) == bytemuck::cast_slice::<T, u8>(b)
}

/// The G-buffer's camera (unjittered) for frame `f`, its depth range reaching `cam_far`.
fn camera_view_proj(f: &Frame, c: &RendererConfig, cam_far: f32) -> glam::Mat4 {
    f.camera
        .projection(c.width, c.height, (cam_far * 1e-5).max(1e-3), cam_far)
        * f.camera.view()
}

/// Buffers the frame's outputs are copied into for reading back.
struct Staging {
    hdr: wgpu::Buffer,
    ldr: wgpu::Buffer,
    direct: wgpu::Buffer,
    indirect: wgpu::Buffer,
}

pub struct Renderer {
    pub gpu: std::sync::Arc<Gpu>,
    pub config: RendererConfig,
    /// How frames are submitted and timed: timestamps where the adapter has them, else
    /// serialized (so that run records keep per-pass times); `Off` for the fastest frames.
    pub profiling: Profiling,
    timestamps: Option<Timestamps>,
    staging: Staging,
    /// Keep what did not change since the last frame (shadow maps, ISM tiles, uploads);
    /// `false` redraws and uploads everything every frame.
    pub reuse: bool,
    /// Leave out of the G-buffer and shadow maps the mesh instances outside a view and the
    /// back faces of closed ones seen from outside (`scene::culling`); `false` draws every
    /// triangle everywhere. What the passes store is the same either way, up to which of two
    /// coplanar faces wins a depth tie.
    pub cull: bool,
    last: Last,
    /// The near-field ray directions in a VPL's frame (see [`ism::near_points`]).
    near_dirs: Vec<Vec3>,
    /// The ISM point set followed by the slots' near-field points.
    points: wgpu::Buffer,
    /// Each slot's offset into the ISM point set.
    offsets: Vec<u32>,
    /// (slot, offset) of the slots whose ISM tiles are redrawn this frame.
    slots: wgpu::Buffer,
    tri_count: usize,
    params: wgpu::Buffer,
    tris: wgpu::Buffer,
    vertices: wgpu::Buffer,
    vpls: wgpu::Buffer,
    lights: wgpu::Buffer,
    /// The passes' GPU state, built in the order of [`GRAPH`].
    pub(crate) passes: Passes,
    /// The buffers read back: what the last passes that write `hdr`, `ldr`, `direct` and
    /// `indirect` leave there.
    outputs: Outputs,
    /// The interleave pattern's shift in x and y (from the seed; each below `interleave`).
    pub interleave_shift: (u32, u32),
}

impl Renderer {
    /// Builds every pass for frames of `points_frame`'s triangles; `points_frame` places the
    /// ISM point set (by area) once.
    pub fn new(
        gpu: std::sync::Arc<Gpu>,
        config: RendererConfig,
        points_frame: &Frame,
    ) -> Result<Renderer> {
        check_config(&config, &gpu.limits)?;
        let c = &config;
        let b = Shared::new(&gpu, c, points_frame)?;
        let mut builder = Builder::new(&gpu, c, points_frame, &b)?;
        let passes = Passes::new(&mut builder)?;
        let outputs = builder.outputs()?;
        // The interleave pattern's shift, from the seed.
        let h = crate::math::mix64(c.seed ^ 0x1e7e_a5ed_0000_0009);
        let interleave_shift = (
            (h % c.interleave as u64) as u32,
            ((h >> 32) % c.interleave as u64) as u32,
        );
        let staging = Staging::new(&gpu, c.width as u64 * c.height as u64);
        let timestamps = has_timestamps(&gpu).then(|| Timestamps::new(&gpu, PASSES.len() as u32));
        let profiling = Profiling::default_for(&gpu);
        Ok(Renderer {
            near_dirs: b.near_dirs,
            points: b.points,
            gpu,
            config,
            profiling,
            timestamps,
            staging,
            reuse: true,
            cull: true,
            last: Last::default(),
            offsets: b.offsets,
            slots: b.slots,
            tri_count: points_frame.tris.len(),
            params: b.params,
            tris: b.tris,
            vertices: b.vertices,
            vpls: b.vpls,
            lights: b.lights,
            passes,
            outputs,
            interleave_shift,
        })
    }

    /// Checks that the frame fits what the renderer was built for.
    /// The near-field ray directions each VPL's points are cast along, in its frame (z along
    /// its normal): what [`GpuFrame::near`] holds for each VPL.
    pub fn near_directions(&self) -> &[Vec3] {
        &self.near_dirs
    }

    /// Near-field points per slot this frame: all of [`Self::near_directions`], or none.
    pub(crate) fn near_points(&self, input: &GpuFrame) -> u32 {
        if input.near.is_empty() {
            0
        } else {
            self.near_dirs.len() as u32
        }
    }

    fn check_input(&self, input: &GpuFrame) -> Result<()> {
        let (f, c) = (input.frame, &self.config);
        if !input.near.is_empty() && input.near.len() != input.vpls.len() * self.near_dirs.len() {
            bail!(
                "{} near-field points for {} VPLs: there must be {} for each, or none",
                input.near.len(),
                input.vpls.len(),
                self.near_dirs.len()
            );
        }
        if f.tris.len() != self.tri_count {
            bail!(
                "the frame has {} triangles but the renderer was built for {}",
                f.tris.len(),
                self.tri_count
            );
        }
        if input.vpls.len() > c.slots as usize
            || input.emitter_samples.len() > c.light_samples as usize
        {
            bail!(
                "{} VPLs / {} light samples exceed the renderer's {} / {}",
                input.vpls.len(),
                input.emitter_samples.len(),
                c.slots,
                c.light_samples
            );
        }
        Ok(())
    }

    /// Uploads the triangles and the vertex buffer unless they are the same bits as last
    /// frame's (and reuse is on); returns whether they are the same bits.
    fn upload_geometry(&mut self, f: &Frame) -> bool {
        let sides = f.sides();
        let side = |i: usize| sides.as_ref().map_or(0.0, |s| s[i] as f32);
        let tris: Vec<Tri> = (0..f.tris.len())
            .map(|i| Tri {
                v0: f.tris[i][0].extend(1.0).to_array(),
                v1: f.tris[i][1].extend(1.0).to_array(),
                v2: f.tris[i][2].extend(1.0).to_array(),
                n: f.normals[i].extend(side(i)).to_array(),
                albedo: f.albedo(i).extend(0.0).to_array(),
                emission: f.emission(i).extend(0.0).to_array(),
            })
            .collect();
        let same_bits = same(&self.last.tris, &tris);
        if !(self.reuse && same_bits) {
            let q = &self.gpu.queue;
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
            self.passes.shadows.upload(&self.gpu, &f.tris, &f.instances);
            self.last.tris = tris;
        }
        same_bits
    }

    /// Uploads the VPLs if any changed and the (slot, point offset) list of the slots whose
    /// ISM tile must be drawn again; returns those slots and whether the VPLs were uploaded.
    fn upload_vpls(&mut self, shaded: &[ShadedVpl], still: bool) -> (Vec<u32>, bool) {
        let vpls: Vec<GpuVpl> = shaded
            .iter()
            .map(|v| {
                // A fan's plane normal in the w's (`common.wgsl`, `GpuVpl`); zeros: none.
                let f = v.fan.unwrap_or(Vec3::ZERO);
                GpuVpl {
                    pos: v.position.extend(f.x).to_array(),
                    normal: v.normal.extend(f.y).to_array(),
                    flux: v.flux.extend(f.z).to_array(),
                }
            })
            .collect();
        // A slot keeps its ISM tile while the geometry is still and its VPL's position and
        // normal are the same bits as last frame's.
        let changed: Vec<u32> = (0..vpls.len())
            .filter(|&s| {
                let old = self.last.vpls.get(s);
                !(still && old.is_some_and(|o| o.pos == vpls[s].pos && o.normal == vpls[s].normal))
            })
            .map(|s| s as u32)
            .collect();
        let q = &self.gpu.queue;
        let uploaded = !(still && same(&self.last.vpls, &vpls));
        if uploaded && !vpls.is_empty() {
            q.write_buffer(&self.vpls, 0, bytemuck::cast_slice(&vpls));
        }
        self.last.vpls = vpls;
        if !changed.is_empty() {
            let pairs: Vec<[u32; 2]> = changed
                .iter()
                .map(|&s| [s, self.offsets[s as usize]])
                .collect();
            q.write_buffer(&self.slots, 0, bytemuck::cast_slice(&pairs));
        }
        (changed, uploaded)
    }

    /// Uploads the emitter samples unless they are the same as last frame's (and reuse is
    /// on); returns whether they are the same.
    fn upload_lights(&mut self, frame: &Frame, samples: &[EmitterSample]) -> bool {
        let size = self.config.shadow_size;
        self.last.lit = super::shadow::lit_boxes(frame, samples);
        let lights: Vec<GpuEmitterSample> = samples
            .iter()
            .zip(&self.last.lit)
            .map(|(s, &lit)| GpuEmitterSample::of(s, lit, size))
            .collect();
        let same_bits = same(&self.last.lights, &lights);
        let kept = self.reuse && same_bits;
        if !lights.is_empty() && !kept {
            self.gpu
                .queue
                .write_buffer(&self.lights, 0, bytemuck::cast_slice(&lights));
        }
        self.last.lights = lights;
        same_bits
    }

    /// Uploads what changed since the last frame and the frame's parameters; returns the
    /// slots whose ISM tiles must be drawn again and what was reused.
    fn upload(
        &mut self,
        input: &GpuFrame,
        far: f32,
        near: f32,
        view_proj: glam::Mat4,
    ) -> Result<(Vec<u32>, Reuse)> {
        self.check_input(input)?;
        let f = input.frame;
        let same_tris = self.upload_geometry(f);
        let still = self.reuse && same_tris;
        let (changed, vpls_uploaded) = self.upload_vpls(input.vpls, still);
        if !changed.is_empty() && !input.near.is_empty() {
            self.gpu.queue.write_buffer(
                &self.points,
                bytes::<ism::Point>(self.config.num_points as u64),
                bytemuck::cast_slice(input.near),
            );
        }
        let same_lights = self.upload_lights(f, input.emitter_samples);
        let lights_kept = self.reuse && same_lights;
        // The history holds as it is while the light is the same (same triangles, same emitter
        // samples); otherwise it goes through the change test.
        let history = if let Some(t) = &mut self.passes.temporal {
            let offset = super::gbuffer::subsample(0, 0, self.config.aa);
            let same = same_tris && same_lights;
            t.upload(&self.gpu, (view_proj, offset), same, input.gradient)
        } else {
            HistoryUse::None
        };
        let c = &self.config;
        let (gw, gh) = c.grid();
        let near_points = self.near_points(input);
        let params = FrameConstants {
            width: gw,
            height: gh,
            num_vpls: input.vpls.len() as u32,
            ism_size: c.ism_size,
            ism_points: c.ism_points,
            num_points: c.num_points,
            num_light_samples: input.emitter_samples.len() as u32,
            shadow_size: c.shadow_size,
            far,
            clamp: input.clamp,
            exposure: c.exposure,
            ism_bias: c.ism_bias,
            cam_pos: f.camera.position.extend(1.0).to_array(),
            shadow_bias: c.shadow_bias,
            near,
            pull_levels: c.pull_levels,
            num_changed: changed.len() as u32,
            interleave: c.interleave,
            shift_x: self.interleave_shift.0 % c.interleave,
            shift_y: self.interleave_shift.1 % c.interleave,
            aa: c.aa,
            near_points,
            textured: self.passes.surface.is_some() as u32,
            near_grid: if near_points > 0 {
                ism::near_grid(c.ism_size, c.pull_levels)
            } else {
                0
            },
            ism_level1: self.passes.ism.level1(),
            direct_clamp: input.direct_clamp,
            direct_split: self.config.split_light_samples as u32,
            pad1: 0,
            pad2: 0,
        };
        self.gpu
            .queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let reuse = Reuse {
            geometry_kept: still,
            lights_kept,
            vpls_uploaded,
            shadow_maps_kept: false,
            ism_tiles_kept: input.vpls.len() as u32 - changed.len() as u32,
            ism_tiles_drawn: changed.len() as u32,
            history_kept: history != HistoryUse::None,
            history_tested: history == HistoryUse::Gradient,
        };
        Ok((changed, reuse))
    }

    /// Records the frame's passes in the order of [`GRAPH`], those that run in this renderer.
    /// Returns whether the shadow maps were kept, what the raster passes drew, and the names
    /// of the passes recorded.
    fn encode_passes(&mut self, rec: &mut Recorder, f: &mut pass::Frame) -> Result<(bool, Drawn)> {
        for p in &GRAPH {
            if p.runs(self) {
                p.encode(self, &mut rec.enc, f)?;
                rec.end_pass(p.name)?;
            }
        }
        Ok((
            !f.shadows_drawn && !f.input.emitter_samples.is_empty(),
            f.drawn,
        ))
    }

    /// The mesh instances the raster passes cull by (none with culling off: all is drawn).
    fn instances<'f>(&self, frame: &'f Frame) -> &'f [crate::scene::culling::Instance] {
        if self.cull {
            &frame.instances
        } else {
            &[]
        }
    }

    /// gbuffer: what the camera sees of the frame's instances, drawn into the G-buffer.
    pub(crate) fn encode_gbuffer(&mut self, enc: &mut wgpu::CommandEncoder, f: &mut pass::Frame) {
        let c = &self.config;
        let tris = self.tri_count as u32;
        let instances = self.instances(f.input.frame);
        // The raster passes leave out the instances outside their view and the back faces of
        // closed ones.
        let (skip, view) = super::gbuffer::camera_view(f.view_proj, c.width, c.height);
        // By the spatial clusters of big instances (`scene::culling::Clusters`), drawn in
        // their order.
        let (clusters, order) = self.passes.shadows.clusters();
        let (runs, indices) = if self.cull {
            (view.cluster_runs(instances, clusters, tris), Some(order))
        } else {
            (view.runs(&[], tris), None)
        };
        let (all, front) = crate::scene::culling::counts(&runs);
        f.drawn.triangles = tris as u64;
        (f.drawn.gbuffer_triangles, f.drawn.gbuffer_front_only) = (all, front);
        let eye = f.input.frame.camera.position;
        self.passes.gbuffer.encode(
            &self.gpu,
            enc,
            (&self.vertices, indices),
            &runs,
            (f.view_proj, skip, eye),
        );
    }

    /// shadow_maps: the emitter samples' hemicube faces (kept while the geometry is still).
    pub(crate) fn encode_shadows(&mut self, enc: &mut wgpu::CommandEncoder, f: &mut pass::Frame) {
        let instances = self.instances(f.input.frame);
        f.shadows_drawn = self.passes.shadows.encode(
            &self.gpu,
            enc,
            (f.input.emitter_samples, &self.last.lit),
            (f.near, f.far),
            (&self.vertices, self.tri_count as u32),
            (instances, self.cull),
            !f.geometry_kept,
        );
        let d = &mut f.drawn;
        (d.shadow_faces, d.shadow_triangles, d.shadow_front_only) = self.passes.shadows.drawn;
    }

    /// The size the indirect light is gathered at: supersampled, one sample per pixel (tile
    /// 0 of the grid, the albedo left to compose); else the grid.
    pub(crate) fn indirect_size(&self) -> (u32, u32) {
        let c = &self.config;
        if c.aa > 1 {
            (c.width, c.height)
        } else {
            c.grid()
        }
    }

    /// Copies the outputs into the staging buffers in the frame's submission, submits, and
    /// reads them back: (HDR, 8-bit RGB, direct and indirect with `components`, seconds per
    /// pass).
    #[allow(clippy::type_complexity)]
    fn read_back(
        &self,
        mut rec: Recorder,
        timestamps: Option<&Timestamps>,
        components: bool,
    ) -> Result<(Hdr, Vec<u8>, Option<(Hdr, Hdr)>, Vec<(&'static str, f64)>)> {
        let c = &self.config;
        let pixels = c.width as u64 * c.height as u64;
        let (hdr_bytes, ldr_bytes) = (bytes::<[f32; 4]>(pixels), bytes::<u32>(pixels));
        let st = &self.staging;
        // The frame and its parts at the output size: resolved, or (aa = 1) as composed.
        let o = &self.outputs;
        let (hdr, ldr, direct, indirect) = (&o.hdr, &o.ldr, &o.direct, &o.indirect);
        let mut reads = vec![(hdr, &st.hdr, hdr_bytes)];
        reads.push((ldr, &st.ldr, ldr_bytes));
        if components {
            reads.push((direct, &st.direct, hdr_bytes));
            reads.push((indirect, &st.indirect, hdr_bytes));
        }
        for &(src, dst, size) in &reads {
            rec.enc.copy_buffer_to_buffer(src, 0, dst, 0, size);
        }
        let serialized = std::mem::take(&mut rec.cpu);
        // The timestamps of every pass ended are resolved at the submission.
        let passes = rec.passes.clone();
        rec.submit();
        let mut mapped: Vec<(&wgpu::Buffer, u64)> = reads.iter().map(|r| (r.1, r.2)).collect();
        let stamped = self.profiling == Profiling::Timestamps && timestamps.is_some();
        if let (true, Some(t)) = (stamped, timestamps) {
            mapped.push((&t.staging, (passes.len() as u64 + 1) * 8));
        }
        let mut data = read_mapped(&self.gpu, &mapped)?;
        let pass_s = match (stamped, timestamps) {
            (true, Some(t)) => {
                let ticks = data.pop().unwrap_or_default();
                t.seconds(bytemuck::cast_slice(&ticks))
            }
            _ => serialized,
        };
        let pass_s = passes.into_iter().zip(pass_s).collect();
        let to_hdr = |bytes: &[u8]| -> Hdr {
            let v: &[[f32; 4]] = bytemuck::cast_slice(bytes);
            Hdr {
                width: c.width,
                height: c.height,
                data: v.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect(),
            }
        };
        let ldr: Vec<u8> = data[1]
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        let parts = components.then(|| (to_hdr(&data[2]), to_hdr(&data[3])));
        Ok((to_hdr(&data[0]), ldr, parts, pass_s))
    }

    /// Renders one frame. With `components`, the direct and indirect images come back too.
    pub fn render(&mut self, input: &GpuFrame, components: bool) -> Result<RenderedImage> {
        let f = input.frame;
        let (lo, hi) = f.bounds();
        // The depth range of the ISMs and hemicubes from the scene alone (every VPL and
        // emitter sample lies in its bounds), so that kept tiles stay valid while the camera
        // moves; the camera's covers the scene from wherever the camera is.
        let far = (hi - lo).length() * 1.5;
        let near = far * 1e-5;
        let cam_far = far.max((f.camera.position - (lo + hi) * 0.5).length() * 3.0);
        let t_upload = Instant::now();
        let view_proj = camera_view_proj(f, &self.config, cam_far);
        let (changed, mut reuse) = self.upload(input, far, near, view_proj)?;
        let upload_s = t_upload.elapsed().as_secs_f64();
        let t_gpu = Instant::now();
        // The recorder borrows the device and the timestamp queries while the passes
        // (the shadow maps' reuse state) change.
        let (gpu, timestamps) = (self.gpu.clone(), self.timestamps.take());
        let recorded = (|| {
            let mut rec = Recorder::new(&gpu, self.profiling, timestamps.as_ref());
            let mut f = pass::Frame {
                input,
                changed_slots: changed.len() as u32,
                geometry_kept: reuse.geometry_kept,
                near,
                far,
                view_proj,
                drawn: Drawn::default(),
                shadows_drawn: false,
            };
            let (kept, drawn) = self.encode_passes(&mut rec, &mut f)?;
            let out = self.read_back(rec, timestamps.as_ref(), components)?;
            Ok::<_, anyhow::Error>((kept, drawn, out))
        })();
        self.timestamps = timestamps;
        if recorded.is_err() {
            // This frame's history, ISM tiles and shadow maps may not have been written: the
            // next frame starts anew (uploads and redraws everything).
            if let Some(t) = &mut self.passes.temporal {
                t.forget();
            }
            self.passes.ism.forget();
            self.last = Last::default();
        }
        let (kept, drawn, (hdr, ldr, parts, pass_s)) = recorded?;
        reuse.shadow_maps_kept = kept;
        let gpu_s = t_gpu.elapsed().as_secs_f64();
        // Upload (CPU), each pass, then what the frame's GPU work took beyond the passes
        // (submission, copies, mapping; without per-pass times: all of the GPU work).
        // Every pass of the graph by name (0 for those that did not run here), when the
        // passes were timed.
        let mut timings = vec![("upload", upload_s)];
        let timed = !pass_s.is_empty();
        timings.extend(GRAPH.iter().filter(|_| timed).map(|p| {
            let s = pass_s
                .iter()
                .find(|(n, _)| *n == p.name)
                .map_or(0.0, |t| t.1);
            (p.name, s)
        }));
        let in_passes: f64 = pass_s.iter().map(|t| t.1).sum();
        timings.push(("readback", (gpu_s - in_passes).max(0.0)));
        let (direct, indirect) = parts.map_or((None, None), |(d, i)| (Some(d), Some(i)));
        Ok(RenderedImage {
            hdr,
            ldr,
            direct,
            indirect,
            timings,
            profiling: self.profiling,
            reused: reuse,
            drawn,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config(width: u32, height: u32, aa: u32) -> RendererConfig {
        let r = crate::config::Render {
            sequence: crate::config::Sequence {
                size: crate::config::Size { width, height },
                ..Default::default()
            },
            quality: crate::config::Quality {
                aa,
                ..Default::default()
            },
            ..Default::default()
        };
        crate::resolve::bounds(&r, 36)
    }

    /// The supersampled buffers are checked against the adapter: a grid past its textures or
    /// an HDR frame past its buffers is refused with the flags to change, before anything is
    /// allocated.
    #[test]
    fn supersampled_sizes_are_checked_with_the_flags_named() {
        let limits = wgpu::Limits::downlevel_defaults(); // 2048 texels, 128 MiB buffers
        check_config(&config(1024, 1024, 2), &limits).unwrap();
        let e = check_config(&config(1024, 1024, 3), &limits)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`aa` 3") && e.contains("3072x3072") && e.contains("lower `aa` or `size`"),
            "{e}"
        );
        // 2048^2 sub-samples of 16 bytes fit 128 MiB buffers exactly; a smaller limit refuses.
        let small = wgpu::Limits {
            max_storage_buffer_binding_size: 32 << 20,
            ..limits.clone()
        };
        let e = check_config(&config(1024, 1024, 2), &small)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`aa` 2") && e.contains("lower `size` or `aa`"),
            "{e}"
        );
        check_config(&config(512, 512, 2), &small).unwrap();
        // `--aa 0` chooses by method (`resolve::aa`): 2 for instant radiosity.
        check_config(&config(64, 64, 0), &limits).unwrap();
        let e = check_config(&config(64, 64, 9), &limits)
            .unwrap_err()
            .to_string();
        assert!(e.contains("`aa`") && e.contains("1 to 8"), "{e}");
    }
}
