//! Stage 4 (and later 5-6): virtual point lights. Light paths leave VPLs on diffuse surfaces.

pub mod paths;

pub use paths::{trace_path, trace_paths, Vpl};
