//! The comparison's reference frames: path-traced once and kept in
//! `CACHE/reference/<scene>_<hash>_<WxH>_<spp>spp_<fps>fps_seed<S>[_camera<hash>]/`, reused frame by frame
//! whenever those settings match. The hash is of the scene's source (the file's bytes, or a
//! built-in's generated glTF), so an edited file, or another file of the same name, gets a
//! reference of its own.

use super::plan::Plan;
use crate::config;
use crate::image::Hdr;
use anyhow::{bail, Result};
use std::path::{Path, PathBuf};

/// The cache folder of a reference.
pub fn dir(cfg: &config::Compare, spec: &str) -> PathBuf {
    let name: String = Path::new(spec)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| spec.to_string())
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let s = &cfg.sequence;
    // A --camera of its own: the same scene seen from elsewhere.
    let camera = s
        .camera
        .map(|c| format!("_camera{:016x}", fnv(c.to_string().as_bytes())))
        .unwrap_or_default();
    cfg.cache.join("reference").join(format!(
        "{name}_{:016x}_{}_{}spp_{}fps_seed{}{camera}",
        source_hash(spec),
        s.size,
        cfg.spp,
        s.fps,
        s.seed
    ))
}

/// FNV-1a of the scene's source: a built-in's generated text, else the file's bytes (0 if
/// unreadable: loading the scene reports that).
fn source_hash(spec: &str) -> u64 {
    let bytes = crate::scene::builtin::generate(spec)
        .map(String::into_bytes)
        .or_else(|| std::fs::read(spec).ok())
        .unwrap_or_default();
    fnv(&bytes)
}

fn fnv(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

fn cached(plan: &Plan, f: u32) -> PathBuf {
    plan.cache
        .join(format!("{}.exr", crate::report::frame_stem(f)))
}

/// How many of the plan's frames are not cached yet.
pub fn missing(plan: &Plan) -> usize {
    plan.numbers
        .iter()
        .filter(|&&f| !cached(plan, f).exists())
        .count()
}

/// The reference frames of the plan, from the cache where present, else traced and cached.
pub fn load_or_render(plan: &Plan, tick: &(dyn Fn() + Sync)) -> Result<Vec<Hdr>> {
    let cfg = &plan.cfg;
    let size = cfg.sequence.size;
    let mut images: Vec<Option<Hdr>> = Vec::with_capacity(plan.numbers.len());
    for &f in &plan.numbers {
        let path = cached(plan, f);
        if !path.exists() {
            images.push(None);
            continue;
        }
        let img = Hdr::read(&path)?;
        if (img.width, img.height) != (size.width, size.height) {
            bail!(
                "{}: cached reference is {}x{}, not {size}",
                path.display(),
                img.width,
                img.height
            );
        }
        images.push(Some(img));
    }
    let todo: Vec<u32> = plan
        .numbers
        .iter()
        .zip(&images)
        .filter(|(_, i)| i.is_none())
        .map(|(&f, _)| f)
        .collect();
    let mut traced = Vec::new();
    crate::commands::reference::trace_frames(
        &plan.scene,
        &cfg.sequence,
        cfg.spp,
        todo,
        tick,
        &mut |f, _, img| {
            crate::report::write_frame(&plan.cache, f, &img, cfg.render.exposure)?;
            traced.push(img);
            Ok(())
        },
    )?;
    let mut traced = traced.into_iter();
    Ok(images
        .into_iter()
        .map(|i| i.unwrap_or_else(|| traced.next().expect("one traced per missing")))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cache_folder_follows_the_scene_source_and_settings() {
        let dir_of = |spec: &str, spp: u32| {
            let c = config::Compare {
                spp,
                ..Default::default()
            };
            dir(&c, spec)
        };
        let root = std::env::temp_dir().join(format!("irad-cache-{}", std::process::id()));
        let (a, b) = (root.join("a"), root.join("b"));
        std::fs::create_dir_all(&a).unwrap();
        std::fs::create_dir_all(&b).unwrap();
        let (fa, fb) = (a.join("scene.gltf"), b.join("scene.gltf"));
        std::fs::write(&fa, "one").unwrap();
        std::fs::write(&fb, "two").unwrap();
        let (sa, sb) = (fa.to_str().unwrap(), fb.to_str().unwrap());
        assert_ne!(dir_of(sa, 256), dir_of(sb, 256), "same name, other file");
        let before = dir_of(sa, 256);
        std::fs::write(&fa, "one, edited").unwrap();
        assert_ne!(dir_of(sa, 256), before, "edited file");
        assert_ne!(dir_of("cornell", 256), dir_of("cornell", 512));
        assert_eq!(dir_of("cornell", 256), dir_of("cornell", 256));
        assert_ne!(dir_of("cornell", 256), dir_of("cornell-orbit", 256));
        // Another --camera, another reference; the same one, the same folder.
        let with_camera = |spec: &str| {
            let mut c = config::Compare::default();
            c.sequence.camera = Some(spec.parse().unwrap());
            dir(&c, "cornell")
        };
        let (c1, c2) = ("0,0,3.9:0,0,0:40", "0,0,3.9:0,0,0:41");
        assert_ne!(with_camera(c1), dir_of("cornell", 256));
        assert_ne!(with_camera(c1), with_camera(c2));
        assert_eq!(with_camera(c1), with_camera(c1));
        std::fs::remove_dir_all(&root).unwrap();
    }
}
