//! The overlays that show the machinery, drawn on the CPU into the image a half shows
//! (docs/view.md, "Overlays"): the VPLs as points coloured by weight, green kept from the last
//! frame and red replaced this frame; each emitter sample's shadow-map faces drawn this frame as
//! short strokes along the faces' axes; the ISM atlas as an inset. Pure functions on sRGB bytes
//! and the frame's data: no device (the atlas is read back by [`super::app::App`]).

use crate::math::luminance;
use crate::scene::{Camera, EmitterSample, Frame};
use crate::vpl::ShadedVpl;
use glam::{Vec2, Vec3};

/// What can be drawn over a half's image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Overlays {
    /// The frame's VPLs as points: green kept, red replaced, brighter the heavier.
    pub vpls: bool,
    /// The shadow-map faces drawn: a stroke from each emitter sample along each face's axis.
    pub shadow_faces: bool,
    /// The ISM atlas (level 0 of the pull-push pyramid, the depths the gather reads) as an
    /// inset in the lower right corner.
    pub ism: bool,
}

/// Which overlay an [`super::app::Input::Overlay`] turns on or off (`--overlay`'s words).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum Overlay {
    /// The VPLs as points, green kept and red replaced, brighter the heavier
    Vpls,
    /// The shadow-map faces drawn: a stroke from each emitter sample along each face's axis
    #[cfg_attr(feature = "cli", value(name = "faces"))]
    ShadowFaces,
    /// The ISM atlas as an inset
    Ism,
}

impl Overlays {
    pub fn set(&mut self, o: Overlay, on: bool) {
        match o {
            Overlay::Vpls => self.vpls = on,
            Overlay::ShadowFaces => self.shadow_faces = on,
            Overlay::Ism => self.ism = on,
        }
    }
}

/// A VPL's point: its pixel, colour and whether it was kept from the last frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mark {
    pub x: i32,
    pub y: i32,
    pub colour: [u8; 3],
    pub kept: bool,
    /// lum(flux): power x albedo x the sampler's weight.
    pub weight: f32,
}

/// The colour of a VPL of weight `t` (0: a sixteenth of the frame's mean weight or less, 0.5
/// the mean, 1: 4 times the mean or more; log scale): green if kept, red if replaced, dark to
/// bright.
pub fn weight_colour(t: f32, kept: bool) -> [u8; 3] {
    let t = t.clamp(0.0, 1.0);
    let lerp = |a: f32, b: f32| (a + (b - a) * t).round() as u8;
    if kept {
        [lerp(0.0, 170.0), lerp(90.0, 255.0), lerp(0.0, 170.0)]
    } else {
        [lerp(110.0, 255.0), lerp(0.0, 170.0), lerp(0.0, 170.0)]
    }
}

/// The VPLs in view as marks, lightest first (so that heavy VPLs are drawn on top). `kept[i]`
/// says whether slot i kept its VPL from the last frame (missing: replaced).
pub fn vpl_marks(cam: &Camera, vpls: &[ShadedVpl], kept: &[bool], w: u32, h: u32) -> Vec<Mark> {
    let weights: Vec<f32> = vpls.iter().map(|v| luminance(v.flux)).collect();
    let mean = weights.iter().map(|&x| x as f64).sum::<f64>() / weights.len().max(1) as f64;
    let mut marks: Vec<Mark> = vpls
        .iter()
        .zip(&weights)
        .enumerate()
        .filter_map(|(i, (v, &wt))| {
            let p = cam.project(v.position, w, h)?;
            let (x, y) = (p.x.floor() as i32, p.y.floor() as i32);
            if x < 0 || y < 0 || x >= w as i32 || y >= h as i32 {
                return None;
            }
            let kept = kept.get(i).copied().unwrap_or(false);
            let t = if mean > 0.0 && wt > 0.0 {
                0.5 + ((wt as f64 / mean).log2() / 8.0) as f32
            } else {
                0.0
            };
            Some(Mark {
                x,
                y,
                colour: weight_colour(t, kept),
                kept,
                weight: wt,
            })
        })
        .collect();
    marks.sort_by(|a, b| a.weight.total_cmp(&b.weight));
    marks
}

/// The half-width of a mark in pixels for an image `h` high (1: 3x3 up to 255 pixels high).
pub fn mark_radius(h: u32) -> i32 {
    1 + (h / 256) as i32
}

/// Draws the marks as squares of [`mark_radius`] into `rgb` (`w` x `h`, RGB bytes).
pub fn draw_marks(rgb: &mut [u8], w: u32, h: u32, marks: &[Mark]) {
    let r = mark_radius(h);
    for m in marks {
        for y in m.y - r..=m.y + r {
            for x in m.x - r..=m.x + r {
                put(rgb, w, h, x, y, m.colour);
            }
        }
    }
}

fn put(rgb: &mut [u8], w: u32, h: u32, x: i32, y: i32, c: [u8; 3]) {
    if x >= 0 && y >= 0 && x < w as i32 && y < h as i32 {
        let i = (y as usize * w as usize + x as usize) * 3;
        rgb[i..i + 3].copy_from_slice(&c);
    }
}

/// The colours of the hemicube faces, by index: front (along the sample's normal) white, the
/// four side faces yellow, cyan, magenta, orange.
pub const FACE_COLOURS: [[u8; 3]; 5] = [
    [255, 255, 255],
    [255, 230, 0],
    [0, 230, 255],
    [255, 0, 255],
    [255, 140, 0],
];

/// The shadow-map faces the renderer draws for `samples` (`crate::gpu::shadow::drawn_faces`
/// over `lit_boxes`, as the `shadow_maps` pass does): (sample position, the face's axis
/// scaled to `length`, face index), and their number.
pub fn shadow_faces(
    frame: &Frame,
    samples: &[EmitterSample],
    size: u32,
    length: f32,
) -> Vec<(Vec3, Vec3, usize)> {
    let lit = crate::gpu::shadow::lit_boxes(frame, samples);
    samples
        .iter()
        .zip(lit)
        .flat_map(|(s, lit)| {
            crate::gpu::shadow::drawn_faces(s, lit, size)
                .into_iter()
                .map(move |(k, (_, _, f), _)| (s.position, f.normalize_or_zero() * length, k))
        })
        .collect()
}

/// Draws each face as a stroke from its sample along its axis (clipped to the part in front
/// of the eye), with a dot at the sample.
pub fn draw_faces(rgb: &mut [u8], w: u32, h: u32, cam: &Camera, faces: &[(Vec3, Vec3, usize)]) {
    let near = 1e-3;
    for &(p, axis, k) in faces {
        let c = FACE_COLOURS[k % FACE_COLOURS.len()];
        let (mut a, mut b) = (p, p + axis);
        let (za, zb) = (
            (a - cam.position).dot(cam.forward),
            (b - cam.position).dot(cam.forward),
        );
        if za < near && zb < near {
            continue;
        }
        if za < near {
            a = a + (b - a) * ((near - za) / (zb - za));
        } else if zb < near {
            b = a + (b - a) * ((near - za) / (zb - za));
        }
        let (Some(pa), Some(pb)) = (cam.project(a, w, h), cam.project(b, w, h)) else {
            continue;
        };
        line(rgb, w, h, pa, pb, c);
        if let Some(q) = cam.project(p, w, h) {
            for (dx, dy) in [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)] {
                put(
                    rgb,
                    w,
                    h,
                    q.x.floor() as i32 + dx,
                    q.y.floor() as i32 + dy,
                    c,
                );
            }
        }
    }
}

/// A line of pixels from `a` to `b` (pixel positions), clipped to the image.
fn line(rgb: &mut [u8], w: u32, h: u32, a: Vec2, b: Vec2, c: [u8; 3]) {
    let n = (b - a).abs().max_element().ceil().min(4.0 * (w + h) as f32) as i32;
    for i in 0..=n.max(1) {
        let p = a + (b - a) * (i as f32 / n.max(1) as f32);
        put(rgb, w, h, p.x.floor() as i32, p.y.floor() as i32, c);
    }
}

/// The ISM atlas as an image: `tiles` tiles of `size`^2 texels in rows of ceil(sqrt(tiles)),
/// from level 0 of the pull-push pyramid (`depth + 4 level`, -1 a hole; `shaders/
/// ism_pullpush.wgsl`): a texel grey by nearness (white near the VPL, black at the far end),
/// a hole dark red. Returns (width, height, RGB bytes).
pub fn atlas_image(values: &[f32], tiles: u32, size: u32) -> (u32, u32, Vec<u8>) {
    let cols = (tiles as f64).sqrt().ceil().max(1.0) as u32;
    let rows = tiles.div_ceil(cols).max(1);
    let (w, h) = (cols * size, rows * size);
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    let per = (size * size) as usize;
    for t in 0..tiles {
        let (tx, ty) = ((t % cols) * size, (t / cols) * size);
        for k in 0..per {
            let Some(&v) = values.get(t as usize * per + k) else {
                continue;
            };
            let c = if v < 0.0 || !v.is_finite() {
                [90, 0, 0]
            } else {
                let depth = v - 4.0 * (v / 4.0).floor();
                let g = (255.0 * (1.0 - depth.clamp(0.0, 1.0))).round() as u8;
                [g, g, g]
            };
            let (x, y) = (tx + k as u32 % size, ty + k as u32 / size);
            let i = ((y * w + x) * 3) as usize;
            rgb[i..i + 3].copy_from_slice(&c);
        }
    }
    (w, h, rgb)
}

/// The inset's box in a `w` x `h` image for an atlas of `aw` x `ah`: (x0, y0, width, height),
/// in the lower right corner, half the image's smaller side wide (the atlas's aspect kept).
pub fn inset_box(w: u32, h: u32, aw: u32, ah: u32) -> (u32, u32, u32, u32) {
    let iw = (w.min(h) / 2).max(1);
    let ih = ((iw as u64 * ah as u64 / aw.max(1) as u64) as u32).clamp(1, h);
    (w - iw, h - ih, iw, ih)
}

/// Draws the atlas into its [`inset_box`]: each pixel the mean of the texels it covers (the
/// nearest texel where the inset is the larger).
pub fn draw_inset(rgb: &mut [u8], w: u32, h: u32, atlas: &(u32, u32, Vec<u8>)) {
    let (aw, ah, a) = atlas;
    let (aw, ah) = (*aw as u64, *ah as u64);
    let (x0, y0, iw, ih) = inset_box(w, h, aw as u32, ah as u32);
    let (iw64, ih64) = (iw as u64, ih as u64);
    for y in 0..ih as u64 {
        let (ya, yb) = (y * ah / ih64, ((y + 1) * ah / ih64).max(y * ah / ih64 + 1));
        for x in 0..iw as u64 {
            let (xa, xb) = (x * aw / iw64, ((x + 1) * aw / iw64).max(x * aw / iw64 + 1));
            let mut sum = [0u64; 3];
            for ty in ya..yb {
                for tx in xa..xb {
                    let s = ((ty * aw + tx) * 3) as usize;
                    for c in 0..3 {
                        sum[c] += a[s + c] as u64;
                    }
                }
            }
            let n = (yb - ya) * (xb - xa);
            let d = (((y0 as u64 + y) * w as u64 + x0 as u64 + x) * 3) as usize;
            for c in 0..3 {
                rgb[d + c] = ((sum[c] + n / 2) / n) as u8;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn project_inverts_the_camera_rays() {
        let cam = Camera::look_at(
            Vec3::new(0.3, 1.0, 4.0),
            Vec3::new(0.0, 0.8, 0.0),
            Vec3::Y,
            0.7,
        );
        for p in [
            Vec2::new(10.5, 20.5),
            Vec2::new(63.2, 1.7),
            Vec2::new(0.5, 47.5),
        ] {
            let d = cam.ray_dir(p, 64, 48);
            let q = cam.project(cam.position + d * 3.0, 64, 48).unwrap();
            assert!((q - p).length() < 1e-3, "{p} {q}");
        }
        assert_eq!(cam.project(cam.position - cam.forward, 64, 48), None);
    }

    #[test]
    fn atlas_and_inset_draw_depths_and_holes() {
        let (w, h, rgb) = atlas_image(&[0.0, 0.5, -1.0, 4.25], 1, 2);
        assert_eq!((w, h), (2, 2));
        assert_eq!(
            rgb,
            vec![255, 255, 255, 128, 128, 128, 90, 0, 0, 191, 191, 191]
        );
        let mut img = vec![0u8; 8 * 8 * 3];
        draw_inset(&mut img, 8, 8, &(w, h, rgb));
        assert_eq!(inset_box(8, 8, 2, 2), (4, 4, 4, 4));
        // The inset's top left texel is the atlas's first, white; outside it nothing changed.
        assert_eq!(img[(4 * 8 + 4) * 3], 255);
        assert_eq!(img[(7 * 8 + 7) * 3..][..3], [191, 191, 191]);
        assert!(img[..4 * 8 * 3].iter().all(|&b| b == 0));
    }
}
