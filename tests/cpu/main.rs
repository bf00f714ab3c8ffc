//! What runs on the CPU alone: the built-in scenes and glTF files (with a fuzzer over the
//! loader), the samplers' estimators, and the shared test helpers themselves. One test
//! binary with a module per subject; `cargo test --release --test cpu MODULE::` runs one.

#[path = "../common/mod.rs"]
mod common;

mod compensation;
mod crevice;
mod emission;
mod environment;
mod helpers;
mod hostile;
mod lights_expected;
mod samplers;
mod scale;
mod scene_files;
mod scene_fuzz;
mod scenes;
mod single_sided;
