//! One pass of the frame as the renderer's graph ([`super::graph::GRAPH`]) declares it, and
//! what the passes of one frame share while they encode.

use super::{Drawn, GpuFrame, Renderer};
use crate::gpu::bindings::Pass;
use anyhow::Result;

/// One pass of the frame.
pub struct FramePass {
    /// Its timing label in run records.
    pub name: &'static str,
    /// Its Rust and WGSL files.
    pub files: &'static str,
    /// When it runs (for the docs); [`FramePass::runs`] decides.
    pub when: &'static str,
    /// The named resources it reads and writes.
    pub reads: &'static [&'static str],
    pub writes: &'static [&'static str],
    /// What it computes (for the docs).
    pub what: &'static str,
    /// Its binding tables, which `gpu::bindings`' tests (their only reader) check against its
    /// WGSL.
    #[cfg_attr(not(test), allow(dead_code))]
    pub(crate) tables: &'static [&'static Pass],
    pub(super) runs: fn(&Renderer) -> bool,
    pub(super) encode: fn(&mut Renderer, &mut wgpu::CommandEncoder, &mut Frame) -> Result<()>,
}

impl FramePass {
    /// Whether the pass runs in `r` (from the renderer's settings and the scene).
    pub fn runs(&self, r: &Renderer) -> bool {
        (self.runs)(r)
    }
    pub(crate) fn encode(
        &self,
        r: &mut Renderer,
        enc: &mut wgpu::CommandEncoder,
        f: &mut Frame,
    ) -> Result<()> {
        (self.encode)(r, enc, f)
    }
}

/// What the passes of one frame share: the frame, the slots whose ISM tiles are redrawn, the
/// depth ranges, and what the raster passes report.
pub(crate) struct Frame<'a, 'b> {
    pub input: &'a GpuFrame<'b>,
    pub changed_slots: u32,
    pub geometry_kept: bool,
    /// The ISMs' and hemicubes' depth range, and the G-buffer's camera.
    pub near: f32,
    pub far: f32,
    pub view_proj: glam::Mat4,
    /// What the raster passes drew, and whether the shadow maps were drawn this frame.
    pub drawn: Drawn,
    pub shadows_drawn: bool,
}
