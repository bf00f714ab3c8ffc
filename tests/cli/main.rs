//! The `irad` binary end to end (each test runs it as a command): its outputs, conventions
//! and errors, what a run does as a whole, and `irad compare`'s report in a browser. One test
//! binary with a module per subject; `cargo test --release --test cli MODULE::` runs one.

#[path = "../common/mod.rs"]
mod common;

mod cli;
mod cluster;
mod environment;
mod near_field;
mod report;
mod runs;
#[cfg(feature = "view")]
mod view;
