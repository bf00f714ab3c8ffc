//! The GPU path on every adapter found here (lavapipe through Vulkan, llvmpipe through GL),
//! held to its CPU twin, to the reference path tracer and to analytic answers. One test
//! binary (linking wgpu once) with a module per subject; `cargo test --release --test gpu
//! MODULE::` runs one of them.

#[path = "../common/mod.rs"]
mod common;

mod compensation;
mod environment;
mod gpu;
mod gpu_aa;
mod gpu_passes;
mod interleave_pattern;
mod punctual;
mod radiosity;
mod scale;
mod single_sided;
mod temporal;
mod textures;
mod thin_gap;
#[cfg(feature = "view")]
mod view;
