//! Linear HDR images (RGB f32), tone mapping, and reading/writing EXR and PNG files.
//! Files are written to a temporary name and renamed, so a file is never half-written.

use anyhow::{bail, Context, Result};
use glam::Vec3;
use std::path::Path;

/// A linear-RGB float image, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Hdr {
    pub width: u32,
    pub height: u32,
    pub data: Vec<Vec3>,
}

impl Hdr {
    pub fn new(width: u32, height: u32) -> Self {
        Hdr {
            width,
            height,
            data: vec![Vec3::ZERO; (width * height) as usize],
        }
    }

    pub fn at(&self, x: u32, y: u32) -> Vec3 {
        self.data[(y * self.width + x) as usize]
    }

    /// The image of `f` applied to this image's and `other`'s pixels pairwise (the same size).
    pub fn zip_map(&self, other: &Hdr, f: impl Fn(Vec3, Vec3) -> Vec3) -> Hdr {
        debug_assert_eq!((self.width, self.height), (other.width, other.height));
        Hdr {
            width: self.width,
            height: self.height,
            data: self
                .data
                .iter()
                .zip(&other.data)
                .map(|(&a, &b)| f(a, b))
                .collect(),
        }
    }

    /// Mean RGB over all pixels.
    pub fn mean(&self) -> Vec3 {
        self.data.iter().copied().sum::<Vec3>() / self.data.len().max(1) as f32
    }

    /// Tone-mapped 8-bit sRGB pixels: `exposure * L`, clamped to [0,1], sRGB transfer.
    pub fn to_srgb8(&self, exposure: f32) -> Vec<u8> {
        self.data
            .iter()
            .flat_map(|c| {
                (*c * exposure)
                    .to_array()
                    .map(|v| (srgb_oetf(v.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8)
            })
            .collect()
    }

    /// The tone-mapped preview as an 8-bit RGB image.
    pub fn to_rgb_image(&self, exposure: f32) -> image::RgbImage {
        image::RgbImage::from_raw(self.width, self.height, self.to_srgb8(exposure))
            .expect("width x height x 3 bytes")
    }

    /// Writes linear float RGB as OpenEXR.
    pub fn write_exr(&self, path: &Path) -> Result<()> {
        let flat: Vec<f32> = self.data.iter().flat_map(|c| c.to_array()).collect();
        let img =
            image::Rgb32FImage::from_raw(self.width, self.height, flat).context("image size")?;
        write_bytes(path, &encode(&img, image::ImageFormat::OpenExr)?)
    }

    /// Writes the tone-mapped preview as PNG.
    pub fn write_png(&self, path: &Path, exposure: f32) -> Result<()> {
        let img = self.to_rgb_image(exposure);
        write_bytes(path, &encode(&img, image::ImageFormat::Png)?)
    }

    /// Reads an EXR (linear) or PNG/other 8-bit file (sRGB decoded to linear).
    pub fn read(path: &Path) -> Result<Hdr> {
        let img = image::open(path)
            .with_context(|| format!("{}: cannot read the image", path.display()))?;
        let is_float = matches!(
            img,
            image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_)
        );
        let rgb = img.to_rgb32f();
        let (width, height) = rgb.dimensions();
        let data = rgb
            .pixels()
            .map(|p| {
                let c = Vec3::from(p.0);
                if is_float {
                    c
                } else {
                    Vec3::new(srgb_eotf(c.x), srgb_eotf(c.y), srgb_eotf(c.z))
                }
            })
            .collect();
        Ok(Hdr {
            width,
            height,
            data,
        })
    }
}

pub fn srgb_oetf(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

pub fn srgb_eotf(v: f32) -> f32 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Writes through `write` to a temporary file beside `path`, then renames it into place.
pub fn atomic_write(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    if name.is_empty() {
        bail!("{}: not a file path", path.display());
    }
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    // Keep the extension last so that encoders chosen by extension still work.
    let tmp = path.with_file_name(format!(".{name}.tmp-{}.{ext}", std::process::id()));
    let result = write(&tmp).and_then(|_| {
        std::fs::rename(&tmp, path).with_context(|| {
            format!(
                "{}: cannot move the finished file into place",
                path.display()
            )
        })
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.with_context(|| format!("{}: cannot write", path.display()))
}

/// An image encoded in memory: the encoders see no file, so a failed write (a full disk) is
/// reported as the OS's error on the file, once, not as the encoder's "format error".
pub fn encode<P, C>(img: &image::ImageBuffer<P, C>, format: image::ImageFormat) -> Result<Vec<u8>>
where
    P: image::Pixel + image::PixelWithColorType,
    [P::Subpixel]: image::EncodableLayout,
    C: std::ops::Deref<Target = [P::Subpixel]>,
{
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, format)
        .with_context(|| format!("encoding a {format:?} image"))?;
    Ok(out.into_inner())
}

/// Writes bytes atomically.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    atomic_write(path, |tmp| {
        std::fs::write(tmp, bytes).map_err(anyhow::Error::from)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exr_round_trip_is_exact_and_png_is_srgb() {
        let dir = std::env::temp_dir().join(format!("irad-img-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut img = Hdr::new(3, 2);
        img.data[1] = Vec3::new(0.25, 2.5, 100.0);
        img.data[5] = Vec3::new(0.05, 0.8, 0.001);
        img.write_exr(&dir.join("a.exr")).unwrap();
        assert_eq!(Hdr::read(&dir.join("a.exr")).unwrap(), img);
        // The PNG's bytes against the sRGB curve worked by hand (IEC 61966-2-1), channel by
        // channel: 0.25 -> 255 (1.055 * 0.25^(1/2.4) - 0.055) = 136.96 -> 137; over 1 -> 255;
        // 0.05 -> 63.19 -> 63; 0.8 -> 231.11 -> 231; 0.001 -> 255 * 12.92 * 0.001 = 3.29 -> 3.
        // A gamma of 2.2 gives (136, 255, 255) and (65, 230, 11); swapped R and B fail too.
        img.write_png(&dir.join("a.png"), 1.0).unwrap();
        let png = image::open(dir.join("a.png")).unwrap().to_rgb8();
        assert_eq!(png.get_pixel(1, 0).0, [137, 255, 255]);
        assert_eq!(png.get_pixel(2, 1).0, [63, 231, 3]);
        assert_eq!(png.get_pixel(0, 0).0, [0, 0, 0]);
        // Exposure scales before the curve: 0.5 x (0.5, 0.1, 0.002) = (0.25, 0.05, 0.001).
        let mut half = Hdr::new(1, 1);
        half.data[0] = Vec3::new(0.5, 0.1, 0.002);
        assert_eq!(half.to_srgb8(0.5), vec![137, 63, 3]);
        // Reading an 8-bit file decodes sRGB: byte 137 is ((137/255 + 0.055) / 1.055)^2.4 =
        // 0.250158, byte 63 is 0.049707, byte 231 is 0.799103, byte 3 is 3/255/12.92 = 0.000911.
        let back = Hdr::read(&dir.join("a.png")).unwrap();
        let want = [0.049707, 0.799103, 0.000911];
        for (got, want) in back.at(2, 1).to_array().into_iter().zip(want) {
            assert!((got - want).abs() < 1e-5, "{} vs {want:?}", back.at(2, 1));
        }
        assert!((back.at(1, 0).x - 0.250158).abs() < 1e-5 && back.at(1, 0).y == 1.0);
        assert!(std::fs::read_dir(&dir).unwrap().all(|e| !e
            .unwrap()
            .file_name()
            .to_string_lossy()
            .contains("tmp")));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
