//! How many shadow-hemicube faces a frame's emitter samples draw, with and without culling
//! the faces that meet no geometry: `cargo run --release --example shadow_faces -- SCENE [T]`.
use irad::gpu::shadow::drawn_faces;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("atrium", |s| s.as_str());
    let t: f32 = args.get(2).map_or(Ok(0.0), |s| s.parse())?;
    let scene = irad::scene::builtin::load(name)
        .transpose()?
        .ok_or_else(|| anyhow::anyhow!("no built-in scene {name}"))?;
    let frame = scene.at(t);
    let samples = frame.emitter_samples(1, 32);
    let needed: usize = samples.iter().map(|s| s.faces()).sum();
    let drawn: usize = samples.iter().map(|s| drawn_faces(s).len()).sum();
    println!(
        "{name} at t = {t}: {} samples, {needed} faces by kind, {drawn} drawn",
        samples.len()
    );
    Ok(())
}
