//! Renders one frame on the GPU with its components and the CPU twin's, for inspection:
//! `twin SCENE FRAME OUTDIR`.
use irad::config;
use irad::frame::Pipeline;
use irad::gpu::Gpu;
use irad::reference::twin;
use irad::scene::builtin;
use irad::trace::Tracer;

fn main() -> anyhow::Result<()> {
    irad::gpu::quiet_mesa_runtime_dir();
    let a: Vec<String> = std::env::args().collect();
    if a.len() != 4 {
        anyhow::bail!("usage: twin SCENE FRAME OUTDIR");
    }
    let (w, h) = (192, 192);
    let scene = builtin::load_any(&a[1])?;
    let f: u32 = a[2].parse()?;
    let out = std::path::Path::new(&a[3]);
    std::fs::create_dir_all(out)?;
    let mut cfg = config::Render::default();
    cfg.sequence.size = config::Size {
        width: w,
        height: h,
    };
    cfg.sampler.candidates = Some(1024);
    cfg.sampler.mh_escape = 0;
    cfg.clamp = Some(0.2);
    let gpu = std::sync::Arc::new(Gpu::new(cfg.backend)?);
    let mut p = Pipeline::new(gpu, scene.clone(), &cfg)?;
    let o = p.render_frame(f, true)?;
    let frame = scene.at(f as f32 / 24.0);
    let tr = Tracer::new(&frame);
    let pts = twin::pixel_points(&frame, &tr, w, h);
    let ind = twin::gather(&frame, &tr, &pts, w, h, &o.selection.shaded, 0.2);
    o.image
        .indirect
        .unwrap()
        .write_png(&out.join("gpu_indirect.png"), 4.0)?;
    ind.write_png(&out.join("cpu_indirect.png"), 4.0)?;
    println!("roughness cpu {:.5}", roughness(&ind));
    let png = irad::image::Hdr::read(&out.join("cpu_indirect.png"))?;
    println!("roughness of its png {:.5}", roughness(&png));
    Ok(())
}

/// Mean |pixel - mean of its 4 neighbours| / mean: high-frequency content of an image.
pub fn roughness(img: &irad::image::Hdr) -> f32 {
    let l = |x: u32, y: u32| irad::math::luminance(img.at(x, y));
    let mut s = 0.0;
    let mut m = 0.0;
    for y in 1..img.height - 1 {
        for x in 1..img.width - 1 {
            s += (l(x, y) - 0.25 * (l(x - 1, y) + l(x + 1, y) + l(x, y - 1) + l(x, y + 1))).abs();
            m += l(x, y);
        }
    }
    s / m
}
