//! Per-frame flicker heat maps: `|e_t - warp(e_(t-1))|` per pixel (see
//! `metrics::warp::flicker_maps`), drawn on one colour scale shared by every run of a
//! comparison so their images can be compared; pixels the warp left out are drawn grey.

use anyhow::{Context, Result};
use std::path::Path;

/// The colour of pixels the warp left out (hidden or off screen at t-1): a grey that the
/// colour ramp never takes.
pub const LEFT_OUT: [u8; 3] = [128, 128, 128];

/// The colour ramp's stops, from 0 to the scale's top: black, purple, orange, pale yellow.
const RAMP: [[f32; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [0.36, 0.07, 0.50],
    [0.93, 0.42, 0.12],
    [1.0, 0.98, 0.72],
];

/// The ramp's colour of `x` in [0, 1] (clamped; NaN is 0).
pub fn colour(x: f32) -> [u8; 3] {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    let s = x * (RAMP.len() - 1) as f32;
    let i = (s as usize).min(RAMP.len() - 2);
    let f = s - i as f32;
    let (a, b) = (RAMP[i], RAMP[i + 1]);
    std::array::from_fn(|c| ((a[c] + (b[c] - a[c]) * f) * 255.0).round() as u8)
}

/// A colour for a per-pixel flicker value on the scale `top` (the ramp's top colour at and
/// above it), or [`LEFT_OUT`].
pub fn pixel(v: Option<f32>, top: f32) -> [u8; 3] {
    match v {
        Some(v) => colour(v / top),
        None => LEFT_OUT,
    }
}

/// The shared scale's top: the 99.5th percentile of every kept pixel's flicker over all the
/// maps given (a few outliers do not wash out the rest), or the largest value if that is 0;
/// 1 when every value is 0 (all black).
pub fn shared_scale<'a>(maps: impl Iterator<Item = &'a [Option<f32>]>) -> f32 {
    let mut all: Vec<f32> = maps.flat_map(|m| m.iter().flatten().copied()).collect();
    if all.is_empty() {
        return 1.0;
    }
    let k = ((all.len() as f64 * 0.995) as usize).min(all.len() - 1);
    let (_, p, _) = all.select_nth_unstable_by(k, |a, b| a.total_cmp(b));
    let p = *p;
    let max = all.iter().copied().fold(0.0f32, f32::max);
    if p > 0.0 {
        p
    } else if max > 0.0 {
        max
    } else {
        1.0
    }
}

/// One frame pair's map as an image.
pub fn image(map: &[Option<f32>], width: u32, height: u32, top: f32) -> image::RgbImage {
    let data = map.iter().flat_map(|&v| pixel(v, top)).collect();
    image::RgbImage::from_raw(width, height, data).expect("map size is width x height")
}

/// Gap between the tiles of a sheet, in pixels (white).
pub const GAP: u32 = 2;

/// Every map tiled in reading order, `cols` to a row, `GAP` white pixels between tiles.
pub fn sheet(
    maps: &[Vec<Option<f32>>],
    width: u32,
    height: u32,
    top: f32,
    cols: u32,
) -> image::RgbImage {
    let cols = cols.max(1).min(maps.len().max(1) as u32);
    let rows = (maps.len() as u32).div_ceil(cols).max(1);
    let mut img = image::RgbImage::from_pixel(
        cols * (width + GAP) - GAP,
        rows * (height + GAP) - GAP,
        image::Rgb([255, 255, 255]),
    );
    for (k, m) in maps.iter().enumerate() {
        let (x0, y0) = (
            (k as u32 % cols) * (width + GAP),
            (k as u32 / cols) * (height + GAP),
        );
        for (i, &v) in m.iter().enumerate() {
            let (x, y) = (i as u32 % width, i as u32 / width);
            img.put_pixel(x0 + x, y0 + y, image::Rgb(pixel(v, top)));
        }
    }
    img
}

/// The colour bar: the ramp from 0 (left) to the scale's top (right), then the left-out grey.
pub fn legend() -> image::RgbImage {
    let (w, h, grey) = (256u32, 14u32, 24u32);
    image::RgbImage::from_fn(w + 8 + grey, h, |x, _| {
        if x < w {
            image::Rgb(colour(x as f32 / (w - 1) as f32))
        } else if x < w + 8 {
            image::Rgb([255, 255, 255])
        } else {
            image::Rgb(LEFT_OUT)
        }
    })
}

/// PNG bytes of `img`, also written to `path`.
pub fn write_png(path: &Path, img: &image::RgbImage) -> Result<Vec<u8>> {
    crate::image::atomic_write(path, |tmp| {
        img.save_with_format(tmp, image::ImageFormat::Png)
            .map_err(anyhow::Error::from)
    })?;
    std::fs::read(path).with_context(|| format!("{}: cannot read back", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::Hdr;
    use crate::metrics::warp::{flicker_maps, warped_f1, Warp};
    use glam::{Vec2, Vec3};

    const W: u32 = 8;
    const H: u32 = 4;

    fn hdr(f: impl Fn(u32, u32) -> f32) -> Hdr {
        Hdr {
            width: W,
            height: H,
            data: (0..W * H).map(|i| Vec3::splat(f(i % W, i / W))).collect(),
        }
    }

    /// An error pattern that moves 1.5 pixels left between frames (the warp reads frame 0
    /// half way between the centres 1 and 2 pixels to the right, bilinearly), plus a known
    /// change: 0.003 everywhere, 0.013 at x = 5. By hand, with e_0 linear in x:
    /// |e_1(x) - (e_0(x + 1) + e_0(x + 2)) / 2| = |e_1(x) - e_0(x + 1.5)| = 0.003 (0.013 at
    /// x = 5); x = 6, 7 came from off screen and are left out.
    #[test]
    fn flicker_map_of_a_moving_error_is_the_hand_computed_value() {
        let e0 = |x: f32, y: u32| 0.05 * x + 0.1 * y as f32;
        let test = vec![
            hdr(|x, y| e0(x as f32, y)),
            hdr(|x, y| e0(x as f32 + 1.5, y) + 0.003 + if x == 5 { 0.01 } else { 0.0 }),
        ];
        let reference = vec![hdr(|_, _| 0.0); 2];
        let shift: Vec<Option<Warp>> = (0..W * H)
            .map(|i| {
                let (x, y) = (i % W, i / W);
                (x + 2 < W).then(|| Warp {
                    q: Vec2::new(x as f32 + 2.0, y as f32 + 0.5),
                    around: [true, true, false, false],
                })
            })
            .collect();
        let motion = vec![vec![None; (W * H) as usize], shift];
        let maps = flicker_maps(&test, &reference, &motion).unwrap();
        assert_eq!(maps.len(), 1);
        for (i, v) in maps[0].iter().enumerate() {
            let x = i as u32 % W;
            match x {
                6 | 7 => assert_eq!(*v, None, "pixel {i}"),
                5 => assert!((v.unwrap() - 0.013).abs() < 1e-6, "pixel {i}: {v:?}"),
                _ => assert!((v.unwrap() - 0.003).abs() < 1e-6, "pixel {i}: {v:?}"),
            }
        }
        // The same quantity warped F1 averages: (5 * 0.003 + 0.013) / 6 per row.
        let w = warped_f1(&test, &reference, &motion).unwrap();
        assert!(
            (w.f1 - (5.0 * 0.003 + 0.013) / 6.0).abs() < 1e-6,
            "{}",
            w.f1
        );
        assert_eq!(w.kept, 6.0 / 8.0, "6 of 8 columns kept");

        // Drawn on the scale 0.013: x = 5 is the ramp's top colour, the rest 0.003 / 0.013 of
        // the way up, the left-out pixels grey; the second tile of a sheet is the same map.
        let m: Vec<Vec<Option<f32>>> = maps
            .iter()
            .map(|m| m.iter().map(|v| v.map(|v| v as f32)).collect())
            .collect();
        let top = 0.013;
        let two = vec![m[0].clone(), m[0].clone()];
        let img = sheet(&two, W, H, top, 2);
        assert_eq!(img.dimensions(), (2 * W + GAP, H));
        for tile in 0..2 {
            let x0 = tile * (W + GAP);
            assert_eq!(img.get_pixel(x0 + 5, 1).0, [255, 250, 184]);
            assert_eq!(img.get_pixel(x0 + 6, 1).0, LEFT_OUT);
            assert_eq!(img.get_pixel(x0 + 7, 3).0, LEFT_OUT);
            // 0.003 / 0.013 = 0.2308 of the ramp: 0.692 of the way from black to purple.
            let c = img.get_pixel(x0 + 1, 2).0;
            let expect = [
                0.36 * 0.6923 * 255.0,
                0.07 * 0.6923 * 255.0,
                0.5 * 0.6923 * 255.0,
            ];
            for k in 0..3 {
                assert!(
                    (c[k] as f32 - expect[k]).abs() <= 1.0,
                    "{c:?} vs {expect:?}"
                );
            }
        }
        assert_eq!(img.get_pixel(W, 0).0, [255, 255, 255], "the gap");
    }

    #[test]
    fn the_shared_scale_ignores_the_top_half_percent() {
        // 1000 values 0.001..1.0: the 99.5th percentile is 0.996; left-out pixels are ignored.
        let a: Vec<Option<f32>> = (1..=500).map(|i| Some(i as f32 / 1000.0)).collect();
        let mut b: Vec<Option<f32>> = (501..=1000).map(|i| Some(i as f32 / 1000.0)).collect();
        b.push(None);
        let s = shared_scale([a.as_slice(), b.as_slice()].into_iter());
        assert!((s - 0.996).abs() < 1e-6, "{s}");
        assert_eq!(
            shared_scale([vec![Some(0.0f32); 4].as_slice()].into_iter()),
            1.0
        );
    }
}
