//! Temporal accumulation (`shaders/temporal.wgsl`, `--accumulate N`): the indirect light of
//! a pixel is the running mean of up to N frames' estimates of its surface point, the
//! earlier ones found by reprojecting the point into the last frame's image (bilinear over
//! the samples on the same surface; a disoccluded pixel starts anew). While the triangles and
//! emitter samples are the same bits as the last frame's, the light being estimated is the
//! same and only the VPLs differ (the camera may move), so the history is used whole; when
//! they changed, the light's temporal gradient (`vpl::gradient`) weighs it (`--history`). With a sampler
//! that draws fresh VPLs each frame (uniform, cdf), a still view's indirect light after n
//! frames is the mean of n independent estimates: n times fewer VPLs' variance. The history
//! ping-pongs between two buffers (running mean and frame count, G-buffer sample), one pass
//! per parity.

use super::bindings::{bytes, gpu_struct, params, read, read_write, texture, Elem, Group, Pass};
use super::common::{FrameConstants, Tri};
use super::{Gpu, PixelPass};
use crate::vpl::gradient::{Gradient, GRID};
use glam::{Mat4, Vec2};

gpu_struct! {
    /// The last frame's camera and the accumulation's settings.
    pub(crate) struct History {
        pub prev_view_proj: [[f32; 4]; 4],
        /// Tile 0's sub-sample offset (x, y), the most frames averaged, and how the last
        /// frame's history is used ([`HistoryUse`] as a number).
        pub offset: [f32; 4],
        /// The gradient grid's width and height (x, y).
        pub grid: [f32; 4],
    }
}

gpu_struct! {
    /// One pixel's history: the running mean (rgb) and its frame count (w), and the G-buffer
    /// sample it is of (position bits, triangle + 1).
    pub(crate) struct HistorySample {
        pub mean: [f32; 4],
        pub sample: [u32; 4],
    }
}

/// What the history does when the light or the objects moved (`--history`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum HistoryMode {
    /// Weighed by the light's temporal gradient (`vpl::gradient`): kept where the light
    /// hardly changed, dropped where it changed entirely
    Gradient,
    /// Dropped everywhere: every such frame starts anew
    Drop,
    /// Kept whole, whatever the change (lags behind it; for comparison)
    Keep,
}

impl std::fmt::Display for HistoryMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            HistoryMode::Gradient => "gradient",
            HistoryMode::Drop => "drop",
            HistoryMode::Keep => "keep",
        })
    }
}

/// How a frame uses the last frame's history.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HistoryUse {
    /// None: the first frame, a changed light with `--history drop`, or after a frame that
    /// failed part-way.
    None = 0,
    /// As it is: the same triangles and emitter samples (so the same light), or `--history
    /// keep`.
    Whole = 1,
    /// Weighed by the light's temporal gradient: the light or the objects moved.
    Gradient = 2,
}

pub(crate) const PASS: Pass = Pass {
    name: "temporal",
    wgsl: include_str!("../../shaders/temporal.wgsl"),
    groups: &[Group {
        stages: wgpu::ShaderStages::COMPUTE,
        bindings: &[
            params("P", &FrameConstants::LAYOUT),
            params("H", &History::LAYOUT),
            read("tris", Elem::Struct(&Tri::LAYOUT)),
            texture("gbuf", wgpu::TextureViewDimension::D2),
            read("current", Elem::Plain(16)),
            read("hist_in", Elem::Struct(&HistorySample::LAYOUT)),
            read_write("output", Elem::Plain(16)),
            read_write("hist_out", Elem::Struct(&HistorySample::LAYOUT)),
            read("gradient", Elem::Plain(4)),
        ],
    }],
};

pub struct Temporal {
    /// Pass `k` reads history buffer `k` and writes buffer `1 - k`.
    passes: [PixelPass; 2],
    settings: wgpu::Buffer,
    /// The light's relative change on the gradient grid (`vpl::gradient`).
    gradient: wgpu::Buffer,
    /// The accumulated indirect light, in the layout of the pass's input.
    pub output: wgpu::Buffer,
    /// Which history buffer the next frame reads.
    parity: usize,
    /// The last frame's view-projection, once a frame was rendered.
    last: Option<Mat4>,
    /// The most frames averaged.
    frames: u32,
    /// What a changed light does to the history.
    mode: HistoryMode,
}

impl Temporal {
    /// The pass over `current` (the gather's or interleave filter's output, indexed as the
    /// sub-sample grid) for the first `pixels` samples of the grid (the rows of tile 0),
    /// averaging up to `frames` frames, a changed light treated as `mode` says.
    pub fn new(
        gpu: &Gpu,
        (params, tris): (&wgpu::Buffer, &wgpu::Buffer),
        gbuf: &wgpu::TextureView,
        current: &wgpu::Buffer,
        pixels: u64,
        (frames, mode): (u32, HistoryMode),
    ) -> Self {
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let size = bytes::<[f32; 4]>(pixels);
        let output = gpu.buffer("indirect accumulated", size, usage);
        let hist_size = bytes::<HistorySample>(pixels);
        let hist = [0, 1].map(|k| gpu.buffer(&format!("history {k}"), hist_size, usage));
        let settings = gpu.buffer(
            "history settings",
            std::mem::size_of::<History>() as u64,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        let cells = (GRID * GRID) as u64;
        let gradient = gpu.buffer(
            "light gradient",
            bytes::<f32>(cells),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        let passes = [0, 1].map(|k| {
            PixelPass::new(
                gpu,
                &PASS,
                &[
                    ("P", params.as_entire_binding()),
                    ("H", settings.as_entire_binding()),
                    ("tris", tris.as_entire_binding()),
                    ("gbuf", wgpu::BindingResource::TextureView(gbuf)),
                    ("current", current.as_entire_binding()),
                    ("hist_in", hist[k].as_entire_binding()),
                    ("output", output.as_entire_binding()),
                    ("hist_out", hist[1 - k].as_entire_binding()),
                    ("gradient", gradient.as_entire_binding()),
                ],
            )
        });
        Temporal {
            passes,
            settings,
            gradient,
            output,
            parity: 0,
            last: None,
            frames,
            mode,
        }
    }

    /// Uploads this frame's settings: the last frame's camera, and how its history is used:
    /// whole when `same_light` (triangles and emitter samples unchanged since it), else as
    /// the mode says, weighed by `gradient` (none: the light hardly changed is not known, so
    /// the history is dropped). `view_proj` is this frame's, `offset` tile 0's sub-sample
    /// offset.
    pub fn upload(
        &mut self,
        gpu: &Gpu,
        (view_proj, offset): (Mat4, Vec2),
        same_light: bool,
        gradient: Option<&Gradient>,
    ) -> HistoryUse {
        let using = match (self.last.is_some(), same_light, self.mode, gradient) {
            (false, ..) => HistoryUse::None,
            (true, true, ..) | (true, false, HistoryMode::Keep, _) => HistoryUse::Whole,
            (true, false, HistoryMode::Gradient, Some(g)) if g.lambda.len() == GRID * GRID => {
                gpu.queue
                    .write_buffer(&self.gradient, 0, bytemuck::cast_slice(&g.lambda));
                HistoryUse::Gradient
            }
            (true, false, ..) => HistoryUse::None,
        };
        let h = History {
            prev_view_proj: self.last.unwrap_or(view_proj).to_cols_array_2d(),
            offset: [offset.x, offset.y, self.frames as f32, using as u32 as f32],
            grid: [GRID as f32, GRID as f32, 0.0, 0.0],
        };
        gpu.queue
            .write_buffer(&self.settings, 0, bytemuck::bytes_of(&h));
        self.last = Some(view_proj);
        using
    }

    /// Drops the history: the next frame starts anew (after a frame that failed part-way).
    pub fn forget(&mut self) {
        self.last = None;
    }

    /// Records the pass over the `width x height` pixels (tile 0 of the grid) and flips the
    /// history buffers for the next frame.
    pub fn encode(&mut self, enc: &mut wgpu::CommandEncoder, width: u32, height: u32) {
        self.passes[self.parity].encode(enc, width, height);
        self.parity = 1 - self.parity;
    }
}
