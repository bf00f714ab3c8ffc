//! Probe: on a fixed frame of a scene, the mean and spread of each sampler's indirect estimate
//! (CPU twin): `mh_probe SCENE TIME`.
use irad::math::luminance;
use irad::reference::twin;
use irad::scene::builtin;
use irad::trace::Tracer;
use irad::vpl::sampler::{Sampler, SamplerKind, SamplerParams};

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let scene = builtin::load_any(&a[1])?;
    let frame = scene.at(a[2].parse()?);
    let tracer = Tracer::new(&frame);
    let (w, h) = (24u32, 24u32);
    let pts = twin::pixel_points(&frame, &tracer, w, h);
    let dmin = 0.19;
    let run = |kind, rate: f32, escape: u32, n: u64, skip: u64| -> Vec<Vec<f32>> {
        let mut s = Sampler::new(SamplerParams {
            kind,
            slots: 256,
            candidates: 1024,
            camera_points: 256,
            eps: 0.05,
            mh_rate: rate,
            mh_escape: escape,
            dmin,
            seed: 3,
            width: 128,
            height: 128,
        });
        (0..n)
            .filter_map(|f| {
                let sel = s.select(&frame, &tracer, f);
                (f >= skip).then(|| {
                    twin::gather(&frame, &tracer, &pts, w, h, &sel.shaded, dmin)
                        .data
                        .iter()
                        .map(|c| luminance(*c))
                        .collect()
                })
            })
            .collect()
    };
    let mean_img = |v: &[Vec<f32>]| -> Vec<f32> {
        (0..v[0].len())
            .map(|i| v.iter().map(|x| x[i]).sum::<f32>() / v.len() as f32)
            .collect()
    };
    let u = run(SamplerKind::Uniform, 1.0, 0, 300, 0);
    let truth = mean_img(&u);
    let mt: f32 = truth.iter().sum::<f32>() / truth.len() as f32;
    for (name, kind, rate, escape, n, skip) in [
        ("uniform", SamplerKind::Uniform, 1.0, 0, 300, 0),
        ("cdf", SamplerKind::Cdf, 1.0, 0, 300, 0),
        ("mh", SamplerKind::Mh, 1.0, 0, 320, 20),
        ("mh-esc8", SamplerKind::Mh, 1.0, 8, 320, 20),
    ] {
        let e = if name == "uniform" {
            u.clone()
        } else {
            run(kind, rate, escape, n, skip)
        };
        let m = mean_img(&e);
        let mean: f32 = m.iter().sum::<f32>() / m.len() as f32;
        let rel: f32 = e
            .iter()
            .map(|x| {
                x.iter()
                    .zip(&truth)
                    .map(|(a, b)| (a - b).powi(2) / (b * b + 0.01))
                    .sum::<f32>()
                    / x.len() as f32
            })
            .sum::<f32>()
            / e.len() as f32;
        println!(
            "{name:8} mean lum {mean:.4} (uniform {mt:.4})  mean relMSE vs uniform-mean {rel:.4}"
        );
    }
    Ok(())
}
