//! irad: instant radiosity for animation sequences, with temporally coherent virtual point
//! lights. One folder per stage of a frame: `scene` (1), `trace` (2), `vpl` (3-6), `gpu` (7),
//! `compensation` (the clamp's bias, after 7), `reference`, `metrics`, `report` (8); `radiosity`: the classical finite-element methods, for
//! comparison.

pub mod check;
#[cfg(feature = "cli")]
pub mod cli;
pub mod commands;
pub mod compensation;
pub mod config;
pub mod frame;
pub mod gpu;
pub mod image;
pub mod interrupt;
#[cfg(test)]
mod layers;
pub mod math;
pub mod metrics;
pub mod radiosity;
pub mod reference;
pub mod report;
pub mod resolve;
pub mod scene;
pub mod trace;
#[cfg(feature = "view")]
pub mod view;
pub mod vpl;
