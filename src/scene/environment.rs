//! The environment: radiance arriving from infinitely far away in every direction where a ray
//! meets no geometry. Either the default sky (a constant radiance [`SKY_RADIANCE`]) or an
//! equirectangular (latitude-longitude) map read from a Radiance `.hdr` or OpenEXR file.
//!
//! Directions map to the map's `(u, v)` in `[0, 1)^2` (u across, v down) with +Y up:
//! `v = theta / pi` with `theta = acos(d.y)` (v = 0 is straight up), and
//! `u = 1/2 + atan2(d.x, -d.z) / (2 pi)`: the image's centre column looks along -Z (where a
//! glTF camera looks by default), u grows toward +X. The map is piecewise constant over its
//! pixels (nearest texel, no filtering), which is what it is sampled by: a pixel is chosen
//! in proportion to its luminance times its solid angle (`luminance x sin(theta)` integrated
//! over the pixel), then a point uniform in solid angle within it, so the pdf is
//! `luminance(pixel) / sum(luminance x solid angle)`. The default sky is the 1 x 1 map, and
//! its sampling is then uniform over the sphere. See docs/math.md, "The environment".

use crate::math::luminance;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// The default sky's radiance (W/m^2/sr, every channel): an unoccluded diffuse surface of
/// albedo `a` under it has radiance `a` exactly, so a white surface is the preview's full
/// white at exposure 1 and crevices are darker (the same as Mitsuba 3's `constant` emitter
/// with its default radiance 1).
pub const SKY_RADIANCE: f32 = 1.0;

/// The widest and tallest map irad reads.
pub const MAX_MAP_SIDE: u32 = 16384;

/// An environment: an equirectangular radiance map with its sampling distribution.
#[derive(Clone, Debug)]
pub struct Environment {
    /// What it is, for messages and run.json: `sky` or the file's path.
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// Radiance per pixel, row 0 at the top (+Y), RGB.
    pub texels: Vec<Vec3>,
    /// Cumulative weights of the rows, normalized to end at 1.
    row_cdf: Vec<f32>,
    /// For each row, the cumulative weights of its pixels, normalized to end at 1.
    col_cdf: Vec<f32>,
    /// sum over pixels of luminance x solid angle.
    lum_integral: f32,
    /// The integral of the radiance over the sphere (RGB, W/m^2).
    pub integral: Vec3,
}

impl Environment {
    /// The default sky: [`SKY_RADIANCE`] in every direction.
    pub fn sky() -> Self {
        Self::uniform(Vec3::splat(SKY_RADIANCE))
    }

    /// A constant radiance `l` in every direction (named `sky`).
    pub fn uniform(l: Vec3) -> Self {
        Self::from_texels("sky".into(), 1, 1, vec![l]).expect("a positive constant")
    }

    /// A map of `width x height` radiance texels (row 0 at the top); an error (without the
    /// setting's name) for a zero size, a negative or non-finite texel, or a black map.
    pub fn from_texels(
        name: String,
        width: u32,
        height: u32,
        texels: Vec<Vec3>,
    ) -> Result<Self, String> {
        if width == 0 || height == 0 {
            return Err(format!("the map is {width} x {height} pixels: it is empty"));
        }
        if width > MAX_MAP_SIDE || height > MAX_MAP_SIDE {
            return Err(format!(
                "the map is {width} x {height} pixels, more than {MAX_MAP_SIDE} on a side"
            ));
        }
        assert_eq!(texels.len(), (width * height) as usize);
        if let Some(i) = texels
            .iter()
            .position(|t| !t.is_finite() || t.min_element() < 0.0)
        {
            return Err(format!(
                "pixel ({}, {}) is {}: radiance must be finite and not negative",
                i as u32 % width,
                i as u32 / width,
                texels[i]
            ));
        }
        let (w, h) = (width as usize, height as usize);
        let mut col_cdf = vec![0f32; w * h];
        let mut rows = vec![0f64; h];
        let mut integral = glam::DVec3::ZERO;
        for j in 0..h {
            let omega = pixel_solid_angle(j, width, height) as f64;
            let mut acc = 0f64;
            for i in 0..w {
                let t = texels[j * w + i];
                acc += luminance(t) as f64 * omega;
                integral += t.as_dvec3() * omega;
                col_cdf[j * w + i] = acc as f32;
            }
            if acc > 0.0 {
                for c in &mut col_cdf[j * w..(j + 1) * w] {
                    *c = (*c as f64 / acc) as f32;
                }
            }
            rows[j] = acc;
        }
        let total: f64 = rows.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return Err("the map is black everywhere: it would light nothing".into());
        }
        let mut acc = 0f64;
        let row_cdf = rows
            .iter()
            .map(|r| {
                acc += r;
                (acc / total) as f32
            })
            .collect();
        Ok(Environment {
            name,
            width,
            height,
            texels,
            row_cdf,
            col_cdf,
            lum_integral: total as f32,
            integral: integral.as_vec3(),
        })
    }

    /// Decodes an equirectangular map from the bytes of a `.hdr` (Radiance RGBE) or `.exr`
    /// file named `name` (`ext`: its extension, lower case); the error says what is wrong
    /// with it (the caller names the setting). `scene::load::read_environment` reads the file.
    pub fn decode(name: &str, ext: &str, bytes: &[u8]) -> Result<Self, String> {
        let format = match ext {
            "hdr" => image::ImageFormat::Hdr,
            "exr" => image::ImageFormat::OpenExr,
            _ => {
                return Err(format!(
                    "{name} is not a .hdr or .exr file (an equirectangular radiance map)"
                ))
            }
        };
        let img = image::load_from_memory_with_format(bytes, format)
            .map_err(|e| format!("{name} cannot be read as a {ext} image: {e}"))?
            .into_rgb32f();
        let (width, height) = img.dimensions();
        let texels = img.pixels().map(|p| Vec3::from_array(p.0)).collect();
        Self::from_texels(name.to_string(), width, height, texels)
            .map_err(|e| format!("{name}: {e}"))
    }

    /// Whether it is the same radiance everywhere.
    pub fn is_uniform(&self) -> bool {
        self.width == 1 && self.height == 1
    }

    /// The radiance arriving from direction `d` (unit, pointing away from the scene).
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        self.texels[self.pixel_of(d)]
    }

    /// The solid-angle pdf with which [`Environment::sample`] picks direction `d`.
    pub fn pdf(&self, d: Vec3) -> f32 {
        luminance(self.texels[self.pixel_of(d)]) / self.lum_integral
    }

    /// A direction drawn from the map's distribution by two uniform numbers: (direction,
    /// radiance from it, solid-angle pdf). `u.x` picks the row (so consecutive strata of
    /// `u.x` are bands of latitude), `u.y` the pixel in it.
    pub fn sample(&self, u: Vec2) -> (Vec3, Vec3, f32) {
        let (w, h) = (self.width as usize, self.height as usize);
        let (j, fy) = pick(&self.row_cdf, u.x.clamp(0.0, 1.0 - 1e-7));
        let row = &self.col_cdf[j * w..(j + 1) * w];
        let (i, fx) = pick(row, u.y.clamp(0.0, 1.0 - 1e-7));
        // Uniform in solid angle within the pixel: uniform in cos(theta) and in phi.
        let (c0, c1) = (
            (PI * j as f32 / h as f32).cos(),
            (PI * (j + 1) as f32 / h as f32).cos(),
        );
        let cos_t = (c0 + (c1 - c0) * fy).clamp(-1.0, 1.0);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let phi = 2.0 * PI * ((i as f32 + fx) / w as f32 - 0.5);
        let d = Vec3::new(sin_t * phi.sin(), cos_t, -sin_t * phi.cos());
        let t = self.texels[j * w + i];
        (d, t, luminance(t) / self.lum_integral)
    }

    /// The texel index of direction `d`.
    fn pixel_of(&self, d: Vec3) -> usize {
        let uv = direction_uv(d);
        let i = ((uv.x * self.width as f32) as usize).min(self.width as usize - 1);
        let j = ((uv.y * self.height as f32) as usize).min(self.height as usize - 1);
        j * self.width as usize + i
    }

    /// The power a light path from the environment carries into a sphere of radius `r`
    /// around the scene: `pi r^2` times the integral of the radiance over the sphere of
    /// directions (pbrt-v4's infinite lights).
    pub fn power(&self, r: f32) -> Vec3 {
        self.integral * (PI * r * r)
    }
}

/// The map coordinates `(u, v)` of direction `d` (see the module's documentation).
pub fn direction_uv(d: Vec3) -> Vec2 {
    let v = d.y.clamp(-1.0, 1.0).acos() / PI;
    let u = 0.5 + d.x.atan2(-d.z) / (2.0 * PI);
    Vec2::new(u.rem_euclid(1.0), v)
}

/// The solid angle of a pixel in row `j` of a `width x height` equirectangular map.
fn pixel_solid_angle(j: usize, width: u32, height: u32) -> f32 {
    let t0 = PI * j as f32 / height as f32;
    let t1 = PI * (j + 1) as f32 / height as f32;
    2.0 * PI / width as f32 * (t0.cos() - t1.cos())
}

/// The entry of a normalized CDF that `u` falls in, and where in it (0..1).
fn pick(cdf: &[f32], u: f32) -> (usize, f32) {
    let i = cdf.partition_point(|&c| c <= u).min(cdf.len() - 1);
    let lo = if i == 0 { 0.0 } else { cdf[i - 1] };
    let p = cdf[i] - lo;
    let f = if p > 0.0 { (u - lo) / p } else { 0.5 };
    (i, f.clamp(0.0, 1.0 - 1e-7))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    fn map() -> Environment {
        // 8 x 4, one bright texel near the top and a dim gradient elsewhere.
        let texels = (0..32)
            .map(|k| {
                if k == 10 {
                    Vec3::new(40.0, 30.0, 20.0)
                } else {
                    Vec3::splat(0.1 + 0.02 * k as f32)
                }
            })
            .collect();
        Environment::from_texels("test".into(), 8, 4, texels).unwrap()
    }

    /// The pdf integrates to 1 over the sphere, the samples land in the texel whose radiance
    /// and pdf they return, and E[L / pdf] is the radiance's integral.
    #[test]
    fn sampling_is_consistent_with_the_pdf_and_the_integral() {
        let env = map();
        let mut r = crate::math::rng(&[3]);
        let n = 200_000;
        let mut sum = Vec3::ZERO;
        let mut pdf_int = 0.0f64;
        for _ in 0..n {
            let (d, l, p) = env.sample(Vec2::new(r.random(), r.random()));
            assert!((d.length() - 1.0).abs() < 1e-4);
            assert_eq!(l, env.radiance(d));
            assert!((p - env.pdf(d)).abs() <= 1e-5 * p);
            sum += l / p;
            // Uniform sphere directions: E[pdf * 4 pi] = 1.
            let z = 1.0 - 2.0 * r.random::<f32>();
            let s = (1.0 - z * z).sqrt();
            let phi = 2.0 * PI * r.random::<f32>();
            pdf_int += (env.pdf(Vec3::new(s * phi.cos(), z, s * phi.sin())) * 4.0 * PI) as f64;
        }
        let est = sum / n as f32;
        println!(
            "E[L/p] {est} vs {}; E[4 pi pdf] {}",
            env.integral,
            pdf_int / n as f64
        );
        // Measured: within 0.0013 (relative); the colour of the bright texel against the
        // grey ones is what varies.
        assert!((est - env.integral).abs().max_element() < 4e-3 * env.integral.max_element());
        assert!((pdf_int / n as f64 - 1.0).abs() < 0.02);
    }

    #[test]
    fn uniform_sky_is_uniform() {
        let env = Environment::sky();
        assert!(env.is_uniform());
        assert!((env.integral - Vec3::splat(4.0 * PI)).abs().max_element() < 1e-5);
        assert!((env.pdf(Vec3::Y) - 1.0 / (4.0 * PI)).abs() < 1e-7);
        // The centre column looks along -Z, +X a quarter turn to the right of it.
        assert!((direction_uv(Vec3::NEG_Z) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        assert!((direction_uv(Vec3::X) - Vec2::new(0.75, 0.5)).length() < 1e-6);
        assert!(direction_uv(Vec3::Y).y < 1e-6);
    }

    #[test]
    fn bad_maps_are_refused_saying_why() {
        let e = |w, h, t: Vec<Vec3>| Environment::from_texels("m".into(), w, h, t).unwrap_err();
        assert!(e(0, 1, vec![]).contains("empty"));
        assert!(e(1, 1, vec![Vec3::new(1.0, f32::NAN, 1.0)]).contains("finite"));
        assert!(e(2, 1, vec![Vec3::ONE, Vec3::new(-1.0, 0.0, 0.0)]).contains("pixel (1, 0)"));
        assert!(e(1, 1, vec![Vec3::ZERO]).contains("black"));
    }
}
