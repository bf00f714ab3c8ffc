//! The GPU's direct and indirect light under an environment against the CPU twin's (the same
//! VPLs, and 4096 environment samples, with ray-cast visibility), over the pixels that see
//! geometry: `env_split SCENE [sky]` (`sky`: put the default sky in any scene; `SS=N`: shadow
//! maps of N texels). See docs/math.md, "The environment".
use irad::config;
use irad::frame::Pipeline;
use irad::gpu::Gpu;
use irad::image::Hdr;
use irad::reference::twin;
use irad::trace::Tracer;

fn main() -> anyhow::Result<()> {
    irad::gpu::quiet_mesa_runtime_dir();
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 2 {
        anyhow::bail!("usage: env_split SCENE [sky]");
    }
    let (w, h) = (96, 96);
    let mut scene = irad::config::load_scene(&a[1])?;
    if a.get(2).is_some_and(|s| s == "sky") {
        scene.environment = Some(std::sync::Arc::new(irad::scene::Environment::sky()));
    }
    let mut cfg = config::Render::default();
    cfg.sequence.size = config::Size {
        width: w,
        height: h,
    };
    cfg.quality.aa = 1;
    if let Ok(s) = std::env::var("SS") {
        cfg.quality.shadow_size = s.parse()?;
    }
    let gpu = std::sync::Arc::new(Gpu::new(cfg.backend)?);
    let mut p = Pipeline::new(gpu, scene.clone(), &cfg)?;
    let o = p.render_frame(0, true)?;
    let frame = scene.at(0.0);
    let tr = Tracer::new(&frame);
    let pts = twin::pixel_points(&frame, &tr, w, h);
    let ind = twin::gather(&frame, &tr, &pts, w, h, &o.selection.shaded, p.params.clamp);
    let dir = twin::direct(&frame, &tr, &pts, w, h, &frame.emitter_samples(5, 4096));
    let mean = |i: &Hdr| twin::mean_over_surfaces(i, &pts);
    let (gd, gi) = (o.image.direct.unwrap(), o.image.indirect.unwrap());
    println!(
        "direct: GPU {:.4}, twin {:.4}; indirect: GPU {:.4}, twin {:.4}",
        mean(&gd),
        mean(&dir),
        mean(&gi),
        mean(&ind)
    );
    Ok(())
}
