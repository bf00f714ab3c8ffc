//! Samplers: which VPLs a frame uses, and their weights.
//!
//! `uniform` is Keller's instant radiosity: fresh light paths every frame, traced until the
//! VPL slots are full; each VPL is weighted by 1 / (paths used).

use super::{trace_path, ShadedVpl, Vpl};
use crate::scene::Frame;
use crate::trace::Tracer;

/// The frame's VPLs and what the run record says about them.
#[derive(Clone, Debug)]
pub struct Selection {
    pub vpls: Vec<Vpl>,
    pub shaded: Vec<ShadedVpl>,
    /// Light paths traced for this frame.
    pub paths: u64,
    /// Fraction of slots whose VPL changed since the last frame.
    pub replaced: f32,
}

/// Path ids of frame f start at f * PATHS_PER_FRAME, so frames draw independent paths.
pub const PATHS_PER_FRAME: u64 = 1 << 32;

/// Uniform sampling: paths `f * 2^32 + k`, k = 0, 1, ... until `slots` VPLs; a path whose VPLs
/// would overflow the slots is not used (so every used path is whole).
pub fn uniform(
    frame: &Frame,
    tracer: &Tracer,
    seed: u64,
    frame_index: u64,
    slots: usize,
) -> Selection {
    let mut vpls = Vec::with_capacity(slots);
    let mut paths = 0u64;
    while vpls.len() < slots && paths < 64 * slots as u64 + 1024 {
        let p = trace_path(frame, tracer, seed, frame_index * PATHS_PER_FRAME + paths);
        if vpls.len() + p.len() > slots {
            break;
        }
        // A path that left no VPL (its light escaped) still counts as a path.
        vpls.extend(p);
        paths += 1;
    }
    let w = 1.0 / paths.max(1) as f32;
    let shaded = vpls.iter().map(|v| ShadedVpl::new(v, w)).collect();
    Selection {
        vpls,
        shaded,
        paths,
        replaced: 1.0,
    }
}
