//! Textures: each glTF texture's image (PNG or JPEG; embedded in a buffer view, a data: URI,
//! or a file beside the scene) decoded to 8-bit sRGB RGBA, with its sampler's wrap modes and
//! magnification filter. An image that is missing or cannot be decoded is a warning naming
//! it, and the materials that use it fall back to their factors.

use super::buffers::Buffers;
use super::{files, Ctx, LoadError};
use crate::scene::texture::{Filter, Texture, Wrap, MAX_SIDE};
use gltf::texture::{MagFilter, WrappingMode};
use std::path::Path;

/// Every texture of the file by index (None: its image could not be read). An image file
/// outside the scene's folder is an error (unless the options allow it), not a warning.
pub(super) fn read(
    cx: &mut Ctx,
    doc: &gltf::Document,
    buffers: &Buffers,
    base: Option<&Path>,
) -> Result<Vec<Option<Texture>>, LoadError> {
    for (i, img) in doc.as_json().images.iter().enumerate() {
        let Some(uri) = img.uri.as_deref().filter(|u| !u.starts_with("data:")) else {
            continue;
        };
        let dir = base.unwrap_or(Path::new("."));
        if files::resolve(dir, uri).is_ok() {
            files::check_inside(dir, uri, &cx.options)
                .map_err(|e| cx.err(format!("image {i} {e}")))?;
        }
    }
    // Each image decoded once, however many textures share it.
    let images: Vec<Option<image::RgbaImage>> = doc
        .images()
        .map(|img| decode(cx, doc, &img, buffers, base))
        .collect();
    Ok(doc
        .textures()
        .map(|t| {
            let img = images.get(t.source().index())?.as_ref()?;
            let s = t.sampler();
            let wrap = |m: WrappingMode| match m {
                WrappingMode::Repeat => Wrap::Repeat,
                WrappingMode::ClampToEdge => Wrap::Clamp,
                WrappingMode::MirroredRepeat => Wrap::Mirror,
            };
            Some(Texture {
                name: t
                    .name()
                    .or(t.source().name())
                    .map_or_else(|| format!("texture {}", t.index()), str::to_string),
                width: img.width(),
                height: img.height(),
                texels: img.pixels().map(|p| p.0).collect(),
                wrap_s: wrap(s.wrap_s()),
                wrap_t: wrap(s.wrap_t()),
                filter: match s.mag_filter() {
                    Some(MagFilter::Nearest) => Filter::Nearest,
                    _ => Filter::Linear,
                },
            })
        })
        .collect())
}

/// One image as RGBA8 (sRGB codes), at most [`MAX_SIDE`] on a side; None (with a warning
/// naming it) when it cannot be had.
fn decode(
    cx: &mut Ctx,
    doc: &gltf::Document,
    img: &gltf::Image,
    buffers: &Buffers,
    base: Option<&Path>,
) -> Option<image::RgbaImage> {
    let what = match img.name() {
        Some(n) => format!("image {} ('{n}')", img.index()),
        None => format!("image {}", img.index()),
    };
    let fail = |cx: &mut Ctx, why: String| {
        cx.warn(format!(
            "{what} {why}: the materials that use it take their factors alone"
        ));
        None
    };
    // The image's JSON as it is: the gltf crate's Image::source unwraps a missing uri, or a
    // bufferView's missing mimeType (fuzzed files panicked there).
    let Some(raw) = doc.as_json().images.get(img.index()) else {
        return fail(cx, "is missing".into());
    };
    let bytes: Vec<u8> = match (&raw.buffer_view, &raw.uri) {
        (Some(v), _) => {
            let Some(view) = doc.views().nth(v.value()) else {
                return fail(cx, "names a bufferView that does not exist".into());
            };
            let data = &buffers.get(view.buffer().index())?.0;
            match data.get(view.offset()..view.offset().saturating_add(view.length())) {
                Some(b) => b.to_vec(),
                None => return fail(cx, "lies outside its buffer".into()),
            }
        }
        (None, Some(uri)) => {
            if let Some(d) = files::data_uri(uri) {
                match d {
                    Ok(b) => b,
                    Err(e) => return fail(cx, e),
                }
            } else {
                let path = match files::resolve(base.unwrap_or(Path::new(".")), uri) {
                    Ok(p) => p,
                    Err(e) => return fail(cx, e),
                };
                let limit = files::MAX_IMAGE_BYTES;
                match files::read_regular(&path, limit + 1) {
                    Ok(b) if b.len() as u64 > limit => {
                        return fail(
                            cx,
                            format!("file {} is larger than {} MiB", path.display(), limit >> 20),
                        )
                    }
                    Ok(b) => b,
                    Err(e) => return fail(cx, format!("file {} {e}", path.display())),
                }
            }
        }
        (None, None) => return fail(cx, "has neither a uri nor a bufferView".into()),
    };
    let decoded = image::ImageReader::new(std::io::Cursor::new(&bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())
        .and_then(|r| r.decode().map_err(|e| e.to_string()));
    let img = match decoded {
        Ok(i) => i.to_rgba8(),
        Err(e) => return fail(cx, format!("cannot be decoded ({e})")),
    };
    if img.width() == 0 || img.height() == 0 {
        return fail(cx, "is empty".into());
    }
    let (w, h) = (img.width(), img.height());
    if w.max(h) > MAX_SIDE {
        let k = MAX_SIDE as f64 / w.max(h) as f64;
        let (nw, nh) = (
            ((w as f64 * k).round() as u32).max(1),
            ((h as f64 * k).round() as u32).max(1),
        );
        cx.warn(format!(
            "textures larger than {MAX_SIDE} texels on a side are downsampled ({what}: {w}x{h} -> {nw}x{nh})"
        ));
        return Some(image::imageops::resize(
            &img,
            nw,
            nh,
            image::imageops::FilterType::Triangle,
        ));
    }
    Some(img)
}
