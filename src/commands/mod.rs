//! The commands behind `irad`'s subcommands, as library calls: each takes its settings from
//! [`crate::config`] (validated), opens at most one GPU device, and writes its outputs.
//! `render`, `reference`, `compare`, `bench`, `metrics` have a module each; `info` and
//! `scenes` are here.

pub mod bench;
pub mod compare;
pub mod metrics;
pub mod reference;
pub mod render;

use crate::report;
use crate::scene::{builtin, Scene};
use anyhow::Result;
use std::path::Path;

/// Loads the scene and prints its warnings.
pub fn load_scene(spec: &str) -> Result<Scene> {
    let scene = builtin::load_any(spec)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}

/// `irad scenes`: the built-in scenes and what each stresses; `--generate DIR` writes them;
/// `irad scenes FILE` inspects one.
pub fn scenes(scene: Option<&str>, generate: Option<&Path>) -> Result<()> {
    if let Some(spec) = scene {
        print!(
            "{}",
            crate::scene::inspect::inspect(&builtin::load_any(spec)?)
        );
        return Ok(());
    }
    if let Some(dir) = generate {
        report::prepare_out_dir(dir)?;
        for b in builtin::BUILTINS {
            let text = builtin::generate(b.name).expect("every built-in has a generator");
            let path = dir.join(format!("{}.gltf", b.name));
            crate::image::write_bytes(&path, text.as_bytes())?;
            println!("wrote {}", path.display());
        }
        return Ok(());
    }
    for b in builtin::BUILTINS {
        let scene = builtin::load(b.name).expect("listed")?;
        let f = scene.at(0.0);
        println!(
            "{:14} {:5} triangles  {:4.1} s  {}",
            b.name,
            f.tris.len(),
            scene.duration(),
            b.stresses
        );
    }
    Ok(())
}

/// `irad info`: the adapters found and the one irad would choose.
pub fn info(backend: crate::gpu::BackendChoice) -> Result<()> {
    let list = crate::gpu::adapters(backend);
    if list.is_empty() {
        println!("no adapters found");
    }
    for (a, usable) in &list {
        println!("{} {a}", if *usable { "usable " } else { "no     " });
    }
    let gpu = crate::gpu::Gpu::new(backend)?;
    println!("chosen: {}", gpu.adapter);
    let l = &gpu.limits;
    println!(
        "limits: storage buffer {} MiB, 2D texture {}, array layers {}",
        l.max_storage_buffer_binding_size >> 20,
        l.max_texture_dimension_2d,
        l.max_texture_array_layers
    );
    Ok(())
}
