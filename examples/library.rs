//! irad as a library: settings filled in Rust, one device, a pipeline, a few frames.
//! `cargo run --release --example library [OUTDIR]` renders frames 0..3 of the animated
//! Cornell box with the mh sampler and prints each frame's mean colour and stage times.

use irad::config;
use irad::frame::Pipeline;
use irad::gpu::Gpu;
use std::sync::Arc;

fn main() -> anyhow::Result<()> {
    irad::gpu::quiet_mesa_runtime_dir();
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "out/library".into());
    let out = std::path::Path::new(&out);

    // 1. Settings: start from the defaults, change what this program needs, validate once.
    let mut cfg = config::Render::default();
    cfg.sequence.size = config::Size {
        width: 128,
        height: 128,
    };
    cfg.vpls = 128;
    cfg.sampler.kind = irad::vpl::sampler::SamplerKind::Mh;
    cfg.validate()?;

    // 2. One device, lent to every pipeline this process makes.
    let gpu = Arc::new(Gpu::new(cfg.backend)?);
    println!("adapter: {}", gpu.adapter);

    // 3. The scene and its pipeline; render frames one by one.
    let scene = irad::commands::load_scene(cfg.scene_name())?;
    let mut pipeline = Pipeline::new(gpu, scene, &cfg)?;
    irad::report::prepare_out_dir(out)?;
    for f in 0..3 {
        let frame = pipeline.render_frame(f, false)?;
        let m = frame.image.hdr.mean();
        let gpu_ms: f64 = frame
            .stages
            .iter()
            .skip_while(|(n, _)| *n != "upload")
            .map(|(_, t)| t * 1e3)
            .sum();
        println!(
            "frame {f}: mean RGB ({:.4}, {:.4}, {:.4}), {} VPLs, {:.1} ms ({gpu_ms:.1} ms GPU)",
            m.x,
            m.y,
            m.z,
            frame.selection.vpls.len(),
            frame.seconds * 1e3
        );
        irad::report::write_frame(out, f, &frame.image.hdr, cfg.exposure)?;
    }
    println!("wrote {}/frame_000[0-2].exr|png", out.display());
    Ok(())
}
