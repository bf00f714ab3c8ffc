//! Where a run's warped flicker comes from: the warped F1 of TEST against REF split into the
//! pixels within one pixel of an emitter (in either frame of a pair) and the rest.
//! `cargo run --release --example flicker_split -- SCENE TEST_DIR REF_DIR FIRST COUNT [FPS]`
//! (REF_DIR may hold halves `a/` and `b/`, averaged).
use anyhow::{Context, Result};
use irad::image::Hdr;
use irad::math::luminance;
use irad::metrics::warp::{motion, pixel_hits};
use irad::trace::Tracer;
use std::path::Path;

fn frames(dir: &Path, first: u32, count: u32) -> Result<Vec<Hdr>> {
    (first..first + count)
        .map(|f| {
            let name = format!("frame_{f:04}.exr");
            if dir.join("a").exists() {
                let a = Hdr::read(&dir.join("a").join(&name))?;
                let b = Hdr::read(&dir.join("b").join(&name))?;
                let mut m = a.clone();
                for (o, x) in m.data.iter_mut().zip(&b.data) {
                    *o = (*o + *x) * 0.5;
                }
                Ok(m)
            } else {
                Hdr::read(&dir.join(name))
            }
        })
        .collect()
}

fn main() -> Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let scene = irad::scene::builtin::load_any(&a[1]).context("scene")?;
    let (first, count): (u32, u32) = (a[4].parse()?, a[5].parse()?);
    let fps: f32 = a.get(6).map_or(Ok(24.0), |s| s.parse())?;
    let test = frames(Path::new(&a[2]), first, count)?;
    let reference = frames(Path::new(&a[3]), first, count)?;
    let (w, h) = (test[0].width, test[0].height);
    let fr: Vec<_> = (first..first + count)
        .map(|f| scene.at(f as f32 / fps))
        .collect();
    let m = motion(&fr, w, h);
    // Pixels within one pixel of an emitter, per frame.
    let near: Vec<Vec<bool>> = fr
        .iter()
        .map(|f| {
            let hits = pixel_hits(f, &Tracer::new(f), w, h);
            let em: Vec<bool> = hits
                .iter()
                .map(|x| x.is_some_and(|x| f.emission(x.tri as usize).max_element() > 0.0))
                .collect();
            (0..(w * h) as i64)
                .map(|i| {
                    let (x, y) = (i % w as i64, i / w as i64);
                    (-1..=1).any(|dy| {
                        (-1..=1).any(|dx| {
                            let (u, v) = (x + dx, y + dy);
                            u >= 0
                                && v >= 0
                                && u < w as i64
                                && v < h as i64
                                && em[(v * w as i64 + u) as usize]
                        })
                    })
                })
                .collect()
        })
        .collect();
    let err = |t: usize| -> Vec<f64> {
        test[t]
            .data
            .iter()
            .zip(&reference[t].data)
            .map(|(i, r)| luminance(*i) as f64 - luminance(*r) as f64)
            .collect()
    };
    let (mut s_em, mut s_rest, mut n_all) = (0.0, 0.0, 0usize);
    let mut n_em = 0usize;
    for t in 1..test.len() {
        let (e, p) = (err(t), err(t - 1));
        for (i, q) in m[t].iter().enumerate() {
            let Some(q) = q else { continue };
            let d = (e[i] - q.read(&p, w)).abs();
            n_all += 1;
            let j = (q.q.y as u32 * w + q.q.x as u32) as usize;
            if near[t][i] || near[t - 1][j] {
                s_em += d;
                n_em += 1;
            } else {
                s_rest += d;
            }
        }
    }
    let n = n_all as f64;
    println!(
        "warped F1 {:.5} = near emitters {:.5} ({:.1}% of kept pixels) + elsewhere {:.5}",
        (s_em + s_rest) / n,
        s_em / n,
        100.0 * n_em as f64 / n,
        s_rest / n
    );
    Ok(())
}
