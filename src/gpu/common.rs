//! The Rust twins of the structs in `shaders/common.wgsl`, which every pass shares. Their
//! layouts are checked against the WGSL in `bindings`' test.

use super::bindings::gpu_struct;

gpu_struct! {
    /// Frame constants, the same uniform buffer for every compute pass.
    pub(crate) struct FrameConstants {
        pub width: u32,
        pub height: u32,
        pub num_vpls: u32,
        pub ism_size: u32,
        pub ism_points: u32,
        pub num_points: u32,
        pub num_light_samples: u32,
        pub shadow_size: u32,
        pub far: f32,
        pub clamp: f32,
        pub exposure: f32,
        pub ism_bias: f32,
        pub cam_pos: [f32; 4],
        pub shadow_bias: f32,
        pub near: f32,
        pub pull_levels: u32,
        /// ISM slots redrawn this frame (the first entries of the slots buffer).
        pub num_changed: u32,
        /// Interleaved gather block side (1: off) and the pattern's shift in x and y.
        pub interleave: u32,
        pub shift_x: u32,
        pub shift_y: u32,
        /// Supersampling: sub-samples per pixel side (width and height above are the
        /// sub-sample grid's, `aa` times the output's).
        pub aa: u32,
        /// Ray-cast near-field points each redrawn ISM slot splats besides its subset of the
        /// point set (stored after the point set, `near_points` per slot; see `ism`).
        pub near_points: u32,
        /// 1: the `surface` pass wrote each sample's albedo and emission (textures, vertex
        /// colours); 0: they are the triangle's.
        pub textured: u32,
        /// Side of the grid of near-field cells of a tile (0: no near-field points): a slot's
        /// near-field point keeps the nearest depth of its cell (see `ism`).
        pub near_grid: u32,
        /// Where level 1 of the ISM pyramid starts (`Ism::level1`; 0: no pull-push levels):
        /// the gather reads it at level 0's holes.
        pub ism_level1: u32,
        /// The distance at which an emitter triangle's sample stops growing as `1/d^2` in the
        /// direct pass, as the gather clamps VPLs (0: not clamped); the clamping-bias
        /// compensation adds back what it leaves out (`compensation`).
        pub direct_clamp: f32,
        /// 1: supersampled, the sub-samples of a pixel split the emitter samples among them
        /// (`RendererConfig::split_light_samples`).
        pub direct_split: u32,
        /// To WGSL's size (a multiple of 16 bytes).
        pub pad1: u32,
        pub pad2: u32,
    }
}

gpu_struct! {
    /// One scene triangle: vertices, unit geometric normal (`n[3]`: its [`Frame::sides`]
    /// class), albedo and emitted radiance.
    ///
    /// [`Frame::sides`]: crate::scene::Frame::sides
    pub(crate) struct Tri {
        pub v0: [f32; 4],
        pub v1: [f32; 4],
        pub v2: [f32; 4],
        pub n: [f32; 4],
        pub albedo: [f32; 4],
        pub emission: [f32; 4],
    }
}

gpu_struct! {
    /// A sample's albedo (alpha in w) and emitted radiance, as the `surface` pass finds them.
    pub(crate) struct Surface {
        pub albedo: [f32; 4],
        pub emission: [f32; 4],
    }
}

gpu_struct! {
    /// A VPL: position, unit normal and weighted flux.
    pub(crate) struct GpuVpl {
        pub pos: [f32; 4],
        pub normal: [f32; 4],
        pub flux: [f32; 4],
    }
}

gpu_struct! {
    /// An emitter sample: position, unit normal and `Le / (pdf * count)`, and the window of
    /// its one shadow face when it has one (`shadow::Window`: centre and scale; zeros if not).
    pub(crate) struct GpuEmitterSample {
        pub pos: [f32; 4],
        pub normal: [f32; 4],
        pub radiance: [f32; 4],
        pub window: [f32; 4],
    }
}
