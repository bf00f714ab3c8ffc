//! The comparison's reference frames: path-traced once and kept in
//! `CACHE/reference/<scene>_<WxH>_<spp>spp_<fps>fps_seed<S>/`, reused frame by frame
//! whenever those settings match.

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
    cfg.cache.join("reference").join(format!(
        "{name}_{}_{}spp_{}fps_seed{}",
        s.size, cfg.spp, s.fps, s.seed
    ))
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
