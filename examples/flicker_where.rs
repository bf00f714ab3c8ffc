//! Where a run's warped flicker comes from: its warped F1 and the reference floor's, split
//! into the pixels next to an emitter's edge, those next to another edge (a change of surface
//! normal in the 3x3 neighbourhood of pixel-centre hits) and the rest.
//!
//! `cargo run --release --example flicker_where -- SCENE WxH TEST REFERENCE`: TEST holds the
//! run's frame_FFFF.exr (frames 0.., 24 fps), REFERENCE an `irad compare` cache folder with
//! its two halves in a/ and b/ (docs/antialiasing.md quotes its output). `PER_FRAME=1` also
//! prints each frame pair's emitter-edge share; `MAP=FILE.png` writes each pixel's flicker
//! less the floor's (red: more, blue: less; 1.0 at 0.01 a frame pair); `RAW=FILE` the same
//! as little-endian f32 a pixel, row by row.
use glam::Vec3;
use irad::image::Hdr;
use irad::metrics::warp;
use irad::trace::Tracer;

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let scene = irad::scene::builtin::load_any(&a[1])?;
    let (w, h) = a[2].split_once('x').unwrap();
    let (w, h): (u32, u32) = (w.parse()?, h.parse()?);
    let test_dir = std::path::Path::new(&a[3]);
    let ref_dir = std::path::Path::new(&a[4]);
    let (nums, test, ra) = irad::metrics::read_pair(test_dir, &ref_dir.join("a"))?;
    let (_, _, rb) = irad::metrics::read_pair(test_dir, &ref_dir.join("b"))?;
    let r: Vec<Hdr> = ra
        .iter()
        .zip(&rb)
        .map(|(x, y)| x.zip_map(y, |p, q| (p + q) * 0.5))
        .collect();
    let twin: Vec<Hdr> = ra
        .iter()
        .zip(&rb)
        .zip(&r)
        .map(|((x, y), r)| irad::metrics::floor::noisy_twin(r, x, y, [1, 1]))
        .collect();
    let frames: Vec<_> = nums.iter().map(|&f| scene.at(f as f32 / 24.0)).collect();
    let motion = warp::motion(&frames, w, h);
    let mt = warp::flicker_maps(&test, &r, &motion)?;
    let mf = warp::flicker_maps(&twin, &r, &motion)?;
    // classes per frame t (1..): 0 inside, 1 emitter edge, 2 other edge
    let mut sum = [[0.0f64; 3]; 2];
    let mut cnt = [0usize; 3];
    let mut kept = 0usize;
    // Per pixel: the run's warped flicker less the floor's, summed over frame pairs (`MAP`).
    let mut excess = vec![0.0f64; (w * h) as usize];
    for t in 1..frames.len() {
        let before = (sum[0][1], sum[1][1]);
        let f = &frames[t];
        let hits = warp::pixel_hits(f, &Tracer::new(f), w, h);
        let key = |i: usize| -> (i64, bool, Vec3) {
            match hits[i] {
                None => (-1, false, Vec3::ZERO),
                Some(p) => {
                    let tri = p.tri as usize;
                    let em = f.emission_at(tri, p.b1, p.b2).max_element() > 0.0;
                    (tri as i64, em, f.normals[tri])
                }
            }
        };
        for y in 0..h as i64 {
            for x in 0..w as i64 {
                let i = (y * w as i64 + x) as usize;
                let (_, em0, n0) = key(i);
                let mut class = 0;
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let (nx, ny) = (x + dx, y + dy);
                        if nx < 0 || ny < 0 || nx >= w as i64 || ny >= h as i64 {
                            continue;
                        }
                        let (_, em, n) = key((ny * w as i64 + nx) as usize);
                        if em != em0 {
                            class = 1;
                        } else if class == 0 && n.dot(n0) < 0.99 {
                            class = 2;
                        }
                    }
                }
                if let (Some(vt), Some(vf)) = (mt[t - 1][i], mf[t - 1][i]) {
                    excess[i] += vt - vf;
                    sum[0][class] += vt;
                    sum[1][class] += vf;
                    cnt[class] += 1;
                    kept += 1;
                }
            }
        }
        if std::env::var("PER_FRAME").is_ok() {
            println!(
                "frame {t}: emitter edges test {:.3} floor {:.3}",
                sum[0][1] - before.0,
                sum[1][1] - before.1
            );
        }
    }
    if let Ok(path) = std::env::var("MAP") {
        // Red where the run flickers more than the floor, blue where less, per frame pair.
        let n = (frames.len() - 1) as f64;
        let mut map = Hdr::new(w, h);
        for (o, &v) in map.data.iter_mut().zip(&excess) {
            let v = (v / n) as f32 * 100.0;
            *o = Vec3::new(v.max(0.0), 0.0, (-v).max(0.0));
        }
        map.write_png(std::path::Path::new(&path), 1.0)?;
    }
    if let Ok(path) = std::env::var("RAW") {
        // Each pixel's excess over the floor a frame pair, as little-endian f32, row by row.
        let n = (frames.len() - 1) as f64;
        let bytes: Vec<u8> = excess
            .iter()
            .flat_map(|&v| ((v / n) as f32).to_le_bytes())
            .collect();
        std::fs::write(&path, bytes)?;
    }
    if let Ok(path) = std::env::var("ERR") {
        // The middle frame's signed error against the reference (red: too bright, blue: too
        // dark; 1.0 at a third of the reference's luminance).
        let t = frames.len() / 2;
        let mut map = Hdr::new(w, h);
        for ((o, a), b) in map.data.iter_mut().zip(&test[t].data).zip(&r[t].data) {
            let lum = |c: &Vec3| c.dot(Vec3::new(0.2126, 0.7152, 0.0722));
            let v = (lum(a) - lum(b)) / (lum(b) + 0.01) * 3.0;
            *o = Vec3::new(v.max(0.0), 0.0, (-v).max(0.0));
        }
        map.write_png(std::path::Path::new(&path), 1.0)?;
    }
    let k = kept as f64;
    let names = ["inside", "emitter edge", "other edge"];
    let (tt, tf): (f64, f64) = (
        sum[0].iter().sum::<f64>() / k,
        sum[1].iter().sum::<f64>() / k,
    );
    println!("total: test {tt:.6} floor {tf:.6}");
    for c in 0..3 {
        println!(
            "{:>13}: {:5.1}% of pixels, test {:.6} floor {:.6} (per pixel {:.5} / {:.5})",
            names[c],
            100.0 * cnt[c] as f64 / k,
            sum[0][c] / k,
            sum[1][c] / k,
            sum[0][c] / cnt[c].max(1) as f64,
            sum[1][c] / cnt[c].max(1) as f64
        );
    }
    Ok(())
}
