//! The references `irad compare` caches (`commands::compare::reference_cache`), looked up for
//! the frame the view shows: a reference exists for it when a cached folder has the view's
//! scene (its source's hash), size, fps, seed, `--camera` (none: the scene's own camera) and
//! environment, and holds both halves of the frame at the view's time. The view then shows
//! each half's error and flicker against it (docs/view.md, "Live flicker").

use crate::commands::compare::{plan, reference_cache};
use crate::config::{self, CameraSpec};
use crate::image::Hdr;
use std::path::{Path, PathBuf};

/// The cache's root (`--cache`) and what was last looked up there.
pub struct References {
    pub root: PathBuf,
    /// The last look-up: its key and the folder found (with its spp).
    found: Option<(String, Option<(PathBuf, u32)>)>,
    /// The last frame read: folder, frame number, image.
    frame: Option<(PathBuf, u32, Option<Hdr>)>,
}

impl References {
    pub fn new(root: PathBuf) -> References {
        References {
            root,
            found: None,
            frame: None,
        }
    }

    /// The reference folder (and its spp) for `cfg`'s scene and sequence seen from `camera`,
    /// the one of the most samples when several are cached.
    pub fn folder(
        &mut self,
        cfg: &config::Render,
        camera: Option<CameraSpec>,
    ) -> Option<(PathBuf, u32)> {
        let mut seq = cfg.sequence.clone();
        seq.camera = camera;
        let spec = cfg
            .sequence
            .scene_or(config::DEFAULT_STILL_SCENE)
            .to_string();
        let key = format!(
            "{spec}|{}|{}|{}|{:?}|{:?}",
            seq.size,
            seq.fps,
            seq.seed,
            seq.camera.map(|c| c.to_string()),
            seq.environment.as_ref().map(|e| e.to_string())
        );
        if let Some((k, f)) = &self.found {
            if *k == key {
                return f.clone();
            }
        }
        let found = find(&self.root, &spec, seq);
        self.found = Some((key, found.clone()));
        found
    }

    /// The reference image of frame `f` in `folder` (spp-weighted mean of its halves), if both
    /// halves are there and readable at `size`.
    pub fn frame(&mut self, folder: &Path, spp: u32, f: u32, size: config::Size) -> Option<Hdr> {
        if let Some((d, g, img)) = &self.frame {
            if d == folder && *g == f {
                return img.clone();
            }
        }
        let stem = format!("{}.exr", crate::report::frame_stem(f));
        let read = |h: &str| {
            Hdr::read(&folder.join(h).join(&stem))
                .ok()
                .filter(|i| (i.width, i.height) == (size.width, size.height))
        };
        let img = match (read("a"), read("b")) {
            (Some(a), Some(b)) => Some(reference_cache::mean_of_halves(&a, &b, plan::halves(spp))),
            _ => None,
        };
        self.frame = Some((folder.to_path_buf(), f, img.clone()));
        img
    }
}

/// The cached folder under `root/reference` that `irad compare` would use for `spec` and `seq`
/// at some spp (the largest found).
fn find(root: &Path, spec: &str, seq: config::Sequence) -> Option<(PathBuf, u32)> {
    let entries = std::fs::read_dir(root.join("reference")).ok()?;
    let mut cmp = config::Compare {
        sequence: seq,
        cache: root.to_path_buf(),
        ..Default::default()
    };
    let mut best: Option<(PathBuf, u32)> = None;
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        // ..._<spp>spp_<fps>fps_...
        let Some(spp) = name
            .split('_')
            .find_map(|p| p.strip_suffix("spp").and_then(|n| n.parse::<u32>().ok()))
        else {
            continue;
        };
        cmp.spp = spp;
        if plan::dir(&cmp, spec) == e.path() && best.as_ref().is_none_or(|b| spp > b.1) {
            best = Some((e.path(), spp));
        }
    }
    best
}

/// A half's frame against the cached reference of its time: relMSE, and the flicker F1 =
/// mean over pixels of |e_t - e_t-1| (`irad metrics`' F1) when the last frame had one too.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AgainstReference {
    /// The reference's samples per pixel and frame number.
    pub spp: u32,
    pub frame: u32,
    pub relmse: f64,
    pub f1: Option<f64>,
    /// Mean F1 over the frames in a row that had one.
    pub mean_f1: f64,
    pub frames: u32,
    /// This frame's error image (for the next frame's F1).
    pub error: Vec<f64>,
}
