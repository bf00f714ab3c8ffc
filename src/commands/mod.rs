//! The commands behind `irad`'s subcommands, as library calls: each takes its settings from
//! [`crate::config`] (validated), opens at most one GPU device, and writes its outputs.
//! `render`, `reference`, `compare`, `bench`, `metrics` have a module each; `info` and
//! `scenes` are here.

/// `print!` that returns the write's error instead of panicking: when the reader of a pipe
/// has gone (`irad scenes FILE | head -1`), the command stops with that error and `irad`'s
/// `main` exits quietly with status 0 (see [`is_closed_pipe`]).
#[macro_export]
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout().lock(), $($t)*)
    }};
}

/// `println!` that returns the write's error instead of panicking (see [`out!`]).
#[macro_export]
macro_rules! outln {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($t)*)
    }};
}

/// Whether `e` is a write to a pipe whose reader has gone (then there is no one to tell).
pub fn is_closed_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

pub mod bench;
pub mod cluster;
pub mod compare;
pub mod metrics;
pub mod reference;
pub mod render;

use crate::report;
use crate::scene::builtin;
use anyhow::Result;
use std::path::Path;

/// Loads the scene and prints its warnings.
pub use crate::config::{load_scene, load_scene_with};

/// `irad scenes`: the built-in scenes and what each stresses; `--generate DIR` writes them;
/// `irad scenes FILE` inspects one.
pub fn scenes(
    scene: Option<&str>,
    generate: Option<&Path>,
    options: &crate::scene::load::LoadOptions,
) -> Result<()> {
    if let Some(spec) = scene {
        crate::out!(
            "{}",
            crate::scene::inspect::inspect(&builtin::load_any_with(spec, options)?)
        )?;
        return Ok(());
    }
    if let Some(dir) = generate {
        report::prepare_out_dir(dir)?;
        for b in builtin::BUILTINS {
            let text = builtin::generate(b.name).expect("every built-in has a generator");
            let path = dir.join(format!("{}.gltf", b.name));
            crate::image::write_bytes(&path, text.as_bytes())?;
            crate::outln!("wrote {}", path.display())?;
        }
        return Ok(());
    }
    for b in builtin::BUILTINS {
        let scene = builtin::load(b.name).expect("listed")?;
        let f = scene.at(0.0);
        crate::outln!(
            "{:14} {:5} triangles  {:4.1} s  {}",
            b.name,
            f.tris.len(),
            scene.duration(),
            b.stresses
        )?;
    }
    Ok(())
}

/// `irad info`: the adapters found and the one irad would choose.
pub fn info(backend: crate::gpu::BackendChoice) -> Result<()> {
    let list = crate::gpu::adapters(backend);
    if list.is_empty() {
        crate::outln!("no adapters found")?;
    }
    for (a, usable) in &list {
        crate::outln!("{} {a}", if *usable { "usable " } else { "no     " })?;
    }
    let gpu = crate::gpu::Gpu::new(backend)?;
    crate::outln!("chosen: {}", gpu.adapter)?;
    let l = &gpu.limits;
    crate::outln!(
        "limits: storage buffer {} MiB, 2D texture {}, array layers {}",
        l.max_storage_buffer_binding_size >> 20,
        l.max_texture_dimension_2d,
        l.max_texture_array_layers
    )?;
    Ok(())
}
