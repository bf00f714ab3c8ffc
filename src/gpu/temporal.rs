//! Temporal accumulation (`shaders/temporal.wgsl`, `--accumulate N`): the indirect light of
//! a pixel is the running mean of up to N frames' estimates of its surface point, the
//! earlier ones found by reprojecting the point into the last frame's image (bilinear over
//! the samples on the same surface; a disoccluded pixel starts anew). It is used only while
//! the triangles and emitter samples are the same bits as the last frame's, so that the light
//! being estimated is the same and only the VPLs differ; the camera may move. With a sampler
//! that draws fresh VPLs each frame (uniform, cdf), a still view's indirect light after n
//! frames is the mean of n independent estimates: n times fewer VPLs' variance. The history
//! ping-pongs between two buffers (running mean and frame count, G-buffer sample), one pass
//! per parity.

use super::bindings::{bytes, gpu_struct, params, read, read_write, texture, Elem, Group, Pass};
use super::common::{FrameConstants, Tri};
use super::{Gpu, PixelPass};
use glam::{Mat4, Vec2};

gpu_struct! {
    /// The last frame's camera and the accumulation's settings.
    pub(crate) struct History {
        pub prev_view_proj: [[f32; 4]; 4],
        /// Tile 0's sub-sample offset (x, y), the most frames averaged, whether the last
        /// frame's history may be used (1) or not (0).
        pub offset: [f32; 4],
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
        ],
    }],
};

pub struct Temporal {
    /// Pass `k` reads history buffer `k` and writes buffer `1 - k`.
    passes: [PixelPass; 2],
    settings: wgpu::Buffer,
    /// The accumulated indirect light, in the layout of the pass's input.
    pub output: wgpu::Buffer,
    /// Which history buffer the next frame reads.
    parity: usize,
    /// The last frame's view-projection, once a frame was rendered.
    last: Option<Mat4>,
    /// The most frames averaged.
    frames: u32,
}

impl Temporal {
    /// The pass over `current` (the gather's or interleave filter's output, indexed as the
    /// sub-sample grid) for the first `pixels` samples of the grid (the rows of tile 0),
    /// averaging up to `frames` frames.
    pub fn new(
        gpu: &Gpu,
        params: &wgpu::Buffer,
        tris: &wgpu::Buffer,
        gbuf: &wgpu::TextureView,
        current: &wgpu::Buffer,
        pixels: u64,
        frames: u32,
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
                ],
            )
        });
        Temporal {
            passes,
            settings,
            output,
            parity: 0,
            last: None,
            frames,
        }
    }

    /// Uploads this frame's settings: the last frame's camera, and whether its history holds
    /// (`same_light`: triangles and emitter samples unchanged since it). `view_proj` is this
    /// frame's, `offset` tile 0's sub-sample offset. Returns whether the history is used.
    pub fn upload(&mut self, gpu: &Gpu, view_proj: Mat4, offset: Vec2, same_light: bool) -> bool {
        let valid = same_light && self.last.is_some();
        let h = History {
            prev_view_proj: self.last.unwrap_or(view_proj).to_cols_array_2d(),
            offset: [offset.x, offset.y, self.frames as f32, valid as u32 as f32],
        };
        gpu.queue
            .write_buffer(&self.settings, 0, bytemuck::bytes_of(&h));
        self.last = Some(view_proj);
        valid
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
