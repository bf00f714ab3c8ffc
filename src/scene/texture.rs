//! Textures: a glTF image with its sampler, kept as 8-bit sRGB texels and sampled by the rule
//! below, which the G-buffer shader (`shaders/gbuffer.wgsl`, `tex_sample`) repeats exactly:
//!
//! - a texel's value is its sRGB colour decoded to linear (alpha stays linear);
//! - texel (i, j) has its centre at uv = ((i + 0.5) / w, (j + 0.5) / h), v pointing down the
//!   image, as glTF says;
//! - NEAREST reads the texel that holds uv; LINEAR blends the four centres around it
//!   (decoded first, then blended);
//! - the wrap mode (REPEAT, CLAMP_TO_EDGE, MIRRORED_REPEAT) is applied to each texel index,
//!   separately in s and t.
//!
//! Minification filters and mipmaps are not modelled: a texture is read at its full resolution
//! (images wider or taller than [`MAX_SIDE`] are downsampled once, at load).

use glam::{Mat3, Vec2, Vec3, Vec4};

/// The largest side of a texture kept in memory (and on the GPU).
pub const MAX_SIDE: u32 = 2048;

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    #[default]
    Repeat,
    Clamp,
    Mirror,
}

impl Wrap {
    /// The texel index for index `i` of a side of `n` texels.
    pub fn index(self, i: i64, n: u32) -> u32 {
        let n = n as i64;
        (match self {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::Clamp => i.clamp(0, n - 1),
            Wrap::Mirror => {
                let k = i.rem_euclid(2 * n);
                if k < n {
                    k
                } else {
                    2 * n - 1 - k
                }
            }
        }) as u32
    }

    /// The code the shader reads (`Texture::flags`).
    pub fn code(self) -> u32 {
        match self {
            Wrap::Repeat => 0,
            Wrap::Clamp => 1,
            Wrap::Mirror => 2,
        }
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Filter {
    Nearest,
    #[default]
    Linear,
}

/// An image and its sampler.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// sRGB-encoded RGBA, row 0 at the top (v = 0).
    pub texels: Vec<[u8; 4]>,
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
    pub filter: Filter,
}

/// sRGB transfer function, 8-bit code to linear (IEC 61966-2-1).
pub fn srgb_to_linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// [`srgb_to_linear`] of every 8-bit code, the same bits: a texel is decoded by lookup (the
/// `powf` of each channel of each of a bilinear sample's four texels was 40% of loading
/// `benches/big_emissive.py`'s model, whose emission means sample its texture 34M times).
static SRGB_TO_LINEAR: std::sync::LazyLock<[f32; 256]> =
    std::sync::LazyLock::new(|| std::array::from_fn(|c| srgb_to_linear(c as u8)));

impl Texture {
    /// Texel (i, j) decoded: linear RGB, linear alpha.
    pub fn texel(&self, i: u32, j: u32) -> Vec4 {
        let [r, g, b, a] = self.texels[(j * self.width + i) as usize];
        let lut = &*SRGB_TO_LINEAR;
        Vec4::new(
            lut[r as usize],
            lut[g as usize],
            lut[b as usize],
            a as f32 / 255.0,
        )
    }

    /// The texture at `uv` (see the module docs).
    pub fn sample(&self, uv: Vec2) -> Vec4 {
        let (w, h) = (self.width, self.height);
        // Texel space, centres at integers; far-off uvs are brought near the origin first
        // (by a multiple of 2, a period of REPEAT and MIRROR; CLAMP saturates anyway).
        let uv = Vec2::new(reduce(uv.x, self.wrap_s), reduce(uv.y, self.wrap_t));
        let x = uv.x as f64 * w as f64 - 0.5;
        let y = uv.y as f64 * h as f64 - 0.5;
        let at = |i: i64, j: i64| self.texel(self.wrap_s.index(i, w), self.wrap_t.index(j, h));
        match self.filter {
            Filter::Nearest => at((x + 0.5).floor() as i64, (y + 0.5).floor() as i64),
            Filter::Linear => {
                let (x0, y0) = (x.floor(), y.floor());
                let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
                let (i, j) = (x0 as i64, y0 as i64);
                let top = at(i, j).lerp(at(i + 1, j), fx);
                let bottom = at(i, j + 1).lerp(at(i + 1, j + 1), fx);
                top.lerp(bottom, fy)
            }
        }
    }

    /// Flags the shader reads: wrap s (bits 0-1), wrap t (bits 2-3), nearest (bit 4).
    pub fn flags(&self) -> u32 {
        self.wrap_s.code()
            | self.wrap_t.code() << 2
            | ((self.filter == Filter::Nearest) as u32) << 4
    }
}

/// `u` brought into [-1, 2]: moved by a multiple of 2 (a period) for REPEAT and MIRROR,
/// clamped for CLAMP (texture coordinates far from the origin would otherwise lose the texel
/// in f32; a NaN reads as 0).
pub fn reduce(u: f32, wrap: Wrap) -> f32 {
    if !u.is_finite() {
        return if u == f32::INFINITY { 2.0 } else { 0.0 };
    }
    match wrap {
        Wrap::Clamp => u.clamp(-1.0, 2.0),
        _ => u - 2.0 * (u * 0.5).floor(),
    }
}

/// A material's use of a texture: which one, which UV set, and KHR_texture_transform as an
/// affine map of the UVs (identity without it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexRef {
    pub texture: usize,
    /// 0 (TEXCOORD_0) or 1 (TEXCOORD_1).
    pub texcoord: u32,
    pub transform: Mat3,
}

impl TexRef {
    /// KHR_texture_transform: uv' = T(offset) R(rotation) S(scale) uv, the rotation turning
    /// +u toward -v (the extension's matrix).
    pub fn transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> Mat3 {
        let (s, c) = rotation.sin_cos();
        let t = Mat3::from_cols(Vec3::X, Vec3::Y, Vec3::new(offset[0], offset[1], 1.0));
        let r = Mat3::from_cols(Vec3::new(c, -s, 0.0), Vec3::new(s, c, 0.0), Vec3::Z);
        let sc = Mat3::from_diagonal(Vec3::new(scale[0], scale[1], 1.0));
        t * r * sc
    }

    /// The transformed UV.
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        self.transform.transform_point2(uv)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tex(w: u32, h: u32, wrap: Wrap, filter: Filter) -> Texture {
        Texture {
            name: "t".into(),
            width: w,
            height: h,
            // Texel k has red k * 40 (codes 0, 40, 80, ...), green 255, alpha 255.
            texels: (0..w * h).map(|k| [(k * 40) as u8, 255, 0, 255]).collect(),
            wrap_s: wrap,
            wrap_t: wrap,
            filter,
        }
    }

    #[test]
    fn srgb_decoding_follows_the_standard() {
        assert_eq!(srgb_to_linear(0), 0.0);
        assert_eq!(srgb_to_linear(255), 1.0);
        // 0.5 encoded (code 188 = 0.7373) is about 0.5 linear; code 10 is on the linear part.
        assert!((srgb_to_linear(188) - 0.502886).abs() < 1e-5);
        assert!((srgb_to_linear(10) - 10.0 / 255.0 / 12.92).abs() < 1e-7);
    }

    /// Texels are decoded by a table: every code of every channel gives the formula's bits.
    #[test]
    fn every_code_decodes_to_the_formulas_bits() {
        let t = Texture {
            name: "codes".into(),
            width: 256,
            height: 1,
            texels: (0..256u32)
                .map(|k| [k as u8, 255 - k as u8, (k * 7) as u8, k as u8])
                .collect(),
            wrap_s: Wrap::Clamp,
            wrap_t: Wrap::Clamp,
            filter: Filter::Nearest,
        };
        for k in 0..256u32 {
            let [r, g, b, a] = t.texels[k as usize];
            let want = [srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b)];
            let got = t.texel(k, 0);
            assert_eq!(
                got.truncate().to_array().map(f32::to_bits),
                want.map(f32::to_bits)
            );
            assert_eq!(got.w, a as f32 / 255.0);
        }
    }

    #[test]
    fn nearest_reads_the_texel_that_holds_uv_and_wraps() {
        let t = tex(4, 2, Wrap::Repeat, Filter::Nearest);
        let red = |uv: Vec2| t.sample(uv).x;
        // Texel (1, 1) is k = 5, red code 200.
        assert_eq!(red(Vec2::new(0.30, 0.70)), srgb_to_linear(200));
        // REPEAT: u = 1.30 is u = 0.30.
        assert_eq!(red(Vec2::new(1.30, 0.70)), srgb_to_linear(200));
        let c = tex(4, 2, Wrap::Clamp, Filter::Nearest);
        // CLAMP: u = 1.9 reads the last column (i = 3), row 0: k = 3.
        assert_eq!(c.sample(Vec2::new(1.9, 0.2)).x, srgb_to_linear(120));
        let m = tex(4, 2, Wrap::Mirror, Filter::Nearest);
        // MIRROR: u = 1.1 is texel index 4 -> 3 (mirrored), row 0.
        assert_eq!(m.sample(Vec2::new(1.1, 0.2)).x, srgb_to_linear(120));
        // u = -0.1 is index -1 -> 0.
        assert_eq!(m.sample(Vec2::new(-0.1, 0.2)).x, srgb_to_linear(0));
    }

    #[test]
    fn linear_blends_decoded_texels_halfway_between_centres() {
        let t = tex(4, 2, Wrap::Clamp, Filter::Linear);
        // Halfway between the centres of texels (1, 0) and (2, 0): u = 0.5, v = 0.25.
        let v = t.sample(Vec2::new(0.5, 0.25)).x;
        let expect = 0.5 * (srgb_to_linear(40) + srgb_to_linear(80));
        assert!((v - expect).abs() < 1e-6, "{v} vs {expect}");
        // At a centre it is that texel.
        assert!((t.sample(Vec2::new(0.375, 0.25)).x - srgb_to_linear(40)).abs() < 1e-6);
    }

    #[test]
    fn texture_transform_is_offset_rotation_scale() {
        // Scale 2, then a quarter turn, then offset (0.5, 0): (1, 0) -> (2, 0) -> (0, -2)
        // -> (0.5, -2) (the extension's rotation turns +u toward -v).
        let r = TexRef {
            texture: 0,
            texcoord: 0,
            transform: TexRef::transform([0.5, 0.0], std::f32::consts::FRAC_PI_2, [2.0, 2.0]),
        };
        let q = r.apply(Vec2::new(1.0, 0.0));
        assert!((q - Vec2::new(0.5, -2.0)).length() < 1e-6, "{q}");
    }
}
