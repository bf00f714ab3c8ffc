//! How many shadow faces a frame's emitter samples draw (of their hemicubes', culled to those
//! that meet the geometry, or one window) and the share of the hemicubes' texels they fill:
//! `cargo run --release --example shadow_faces -- SCENE [T]`.
use irad::gpu::shadow::{drawn_faces, lit_boxes};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("atrium", |s| s.as_str());
    let t: f32 = args.get(2).map_or(Ok(0.0), |s| s.parse())?;
    let scene = irad::scene::builtin::load(name)
        .transpose()?
        .ok_or_else(|| anyhow::anyhow!("no built-in scene {name}"))?;
    let frame = scene.at(t);
    let samples = frame.emitter_samples(1, 32);
    let needed: usize = samples.iter().map(irad::gpu::shadow::faces).sum();
    let lit = lit_boxes(&frame, &samples);
    let faces: Vec<_> = samples
        .iter()
        .zip(lit)
        .flat_map(|(s, lit)| drawn_faces(s, lit, 256))
        .collect();
    let texels: u64 = faces.iter().map(|f| f.2[0] as u64 * f.2[1] as u64).sum();
    println!(
        "{name} at t = {t}: {} samples, {needed} faces by kind, {} drawn, {:.2} of their \
         texels at 256 x 256",
        samples.len(),
        faces.len(),
        texels as f64 / (needed as f64 * 65536.0)
    );
    Ok(())
}
