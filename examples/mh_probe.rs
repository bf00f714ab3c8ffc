//! Probe: flicker against error of the samplers on a scene's animation, on the CPU twin
//! (exact visibility, no GPU): `mh_probe SCENE CONFIG...` with CONFIG `kind[:mh_rate]`
//! (kind: uniform, cdf, mh, frozen, rejection). Frames 0..24 at 24 fps, 256 VPLs, seed 7,
//! 32x32 pixels (IRAD_PROBE_SIZE, IRAD_PROBE_FRAMES override; IRAD_PROBE_SEEDS averages seeds
//! 7, 8, ...; IRAD_PROBE_M sets M / N, default 4). Each image is emission +
//! direct (32 emitter samples, ray-traced shadows) + indirect; the reference's indirect is
//! `frozen` with 16384 VPLs (the same paths in every frame, so its own noise hardly
//! flickers), cached under /work/refcache. Prints relMSE, flicker F1 and VPLs replaced.
use anyhow::Context;
use irad::image::Hdr;
use irad::reference::twin;
use irad::scene::{builtin, Frame};
use irad::trace::Tracer;
use irad::vpl::sampler::knobs::SamplerKnobs;
use irad::vpl::sampler::{Sampler, SamplerKind, SamplerParams};

fn env(name: &str, default: u32) -> u32 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn params(
    kind: SamplerKind,
    slots: usize,
    rate: f32,
    clamp: f32,
    seed: u64,
    size: u32,
) -> SamplerParams {
    SamplerParams {
        kind,
        slots,
        candidates: env("IRAD_PROBE_M", 4) as usize * slots,
        clamp,
        seed,
        width: size,
        height: size,
        knobs: SamplerKnobs {
            camera_points: 256,
            eps: Some(0.05),
            mh_rate: rate,
            mh_follow: 0.0,
            mh_escape: 8,
            smc_rate: 0.05,
            smc_follow: 0.0,
            ..SamplerKnobs::default()
        },
    }
}

fn add(a: &Hdr, b: &Hdr) -> Hdr {
    Hdr {
        width: a.width,
        height: a.height,
        data: a.data.iter().zip(&b.data).map(|(x, y)| *x + *y).collect(),
    }
}

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let name = a.get(1).context("usage: mh_probe SCENE CONFIG...")?;
    let scene = builtin::load_any(name)?;
    let size = env("IRAD_PROBE_SIZE", 32);
    let frames = env("IRAD_PROBE_FRAMES", 24);
    let seeds = env("IRAD_PROBE_SEEDS", 1).max(1);
    let (lo, hi) = scene.at(0.0).bounds();
    let clamp = 0.02 * (hi - lo).length();
    // The frames, their tracer, pixel points, and emission + direct light.
    let setup: Vec<(Frame, Tracer, Vec<Option<twin::SurfacePoint>>, Hdr)> = (0..frames)
        .map(|f| {
            let frame = scene.at(f as f32 / 24.0);
            let tracer = Tracer::new(&frame);
            let pts = twin::pixel_points(&frame, &tracer, size, size);
            let lights = frame.emitter_samples(7, 32);
            let base = add(
                &twin::emission(&frame, &pts, size, size),
                &twin::direct(&frame, &tracer, &pts, size, size, &lights),
            );
            (frame, tracer, pts, base)
        })
        .collect();
    let render = |p: SamplerParams| -> (Vec<Hdr>, f32) {
        let mut s = Sampler::new(p);
        let mut replaced = 0.0;
        let imgs = setup
            .iter()
            .enumerate()
            .map(|(f, (frame, tracer, pts, base))| {
                let sel = s.select(frame, tracer, f as u64);
                if f > 0 {
                    replaced += sel.replaced;
                }
                add(
                    base,
                    &twin::gather(frame, tracer, pts, size, size, &sel.shaded, clamp),
                )
            })
            .collect();
        (imgs, replaced / (frames.max(2) - 1) as f32)
    };
    let cache = std::path::PathBuf::from(format!("/work/refcache/twin-{name}-{size}-{frames}.bin"));
    let reference: Vec<Hdr> = match std::fs::read(&cache) {
        Ok(bytes) => {
            let v: Vec<f32> = bytes
                .chunks(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect();
            v.chunks((size * size * 3) as usize)
                .map(|c| Hdr {
                    width: size,
                    height: size,
                    data: c
                        .chunks(3)
                        .map(|x| glam::Vec3::new(x[0], x[1], x[2]))
                        .collect(),
                })
                .collect()
        }
        Err(_) => {
            let (r, _) = render(params(SamplerKind::Frozen, 16384, 1.0, clamp, 1001, size));
            let bytes: Vec<u8> = r
                .iter()
                .flat_map(|h| h.data.iter().flat_map(|c| c.to_array()))
                .flat_map(|x| x.to_le_bytes())
                .collect();
            std::fs::create_dir_all("/work/refcache")?;
            std::fs::write(&cache, bytes)?;
            r
        }
    };
    let numbers: Vec<u32> = (0..frames).collect();
    let frames_only: Vec<Frame> = setup.iter().map(|s| s.0.clone()).collect();
    let motion = irad::metrics::warp::motion(&frames_only, size, size);
    for c in &a[2..] {
        let mut it = c.split(':');
        let kind = <SamplerKind as clap::ValueEnum>::from_str(it.next().unwrap_or(""), true)
            .map_err(anyhow::Error::msg)?;
        let rate: f32 = it.next().map(|x| x.parse()).transpose()?.unwrap_or(1.0);
        let t = std::time::Instant::now();
        let (mut rel, mut f1, mut rep, mut first) = (0.0, 0.0, 0.0, String::new());
        let mut wf1 = 0.0;
        for seed in 7..7 + seeds as u64 {
            let (imgs, replaced) = render(params(kind, 256, rate, clamp, seed, size));
            let m = irad::metrics::sequence(&numbers, &imgs, &reference)?;
            if seed == 7 {
                first = format!("seed 7: {:.5} {:.5}", m.mean_rel_mse, m.flicker_f1);
            }
            rel += m.mean_rel_mse / seeds as f64;
            wf1 += irad::metrics::warp::warped_f1(&imgs, &reference, &motion)?.f1 / seeds as f64;
            f1 += m.flicker_f1 / seeds as f64;
            rep += replaced / seeds as f32;
        }
        println!(
            "{name} {c:14} relMSE {rel:.5} F1 {f1:.5} warped {wf1:.5} replaced {rep:.3} ({first}; {:.1} s)",
            t.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
