//! The comparison's reference frames, traced as two independent halves so that the reference
//! can measure its own noise (the floor of every figure, see [`crate::metrics::floor`]). Half
//! `a` has `ceil(spp / 2)` samples a pixel and half `b` `floor(spp / 2)`, each with its own seed
//! derived from `--seed`; the reference is their spp-weighted mean, so it is a `spp`-sample
//! estimate like any other. The halves are kept in
//! `CACHE/reference/<scene>_<hash>_<WxH>_<spp>spp_<fps>fps_seed<S>_halves<A>+<B>[_camera<hash>]/{a,b}/`
//! and reused frame by frame whenever those settings match. The hash is of the scene's
//! source (the file's bytes, or a built-in's generated glTF), so an edited file, or another
//! file of the same name, gets a reference of its own, and so does another `--camera`. Caches written before the halves (one
//! image a frame, folder name without `_halves`) are never matched, so never misread.

use super::plan::{halves, Plan};
use crate::config;
use crate::image::Hdr;
use anyhow::Result;
use std::path::PathBuf;

/// The seed of half `h` (0: a, 1: b) of a reference traced with `seed`: two independent
/// streams, neither equal to `seed`'s own nor to another seed's halves.
pub fn half_seed(seed: u64, h: usize) -> u64 {
    crate::math::stream_seed(&[seed, 0x4a1f_0000 + h as u64])
}

/// The reference, its two halves and their samples per pixel.
pub struct CachedReference {
    /// The spp-weighted mean of the halves, frame by frame.
    pub frames: Vec<Hdr>,
    pub halves: [Vec<Hdr>; 2],
    pub spp: [u32; 2],
}

impl CachedReference {
    /// The reference's own noise for the plan's frames: what a perfect renderer would
    /// measure (its warped flicker along `motion`).
    pub fn floor(
        &self,
        plan: &Plan,
        motion: &[Vec<Option<crate::metrics::warp::Warp>>],
    ) -> Result<crate::metrics::floor::Floor> {
        crate::metrics::floor::floor(
            &plan.numbers,
            &self.frames,
            [&self.halves[0], &self.halves[1]],
            self.spp,
            Some(motion),
        )
    }
}

const HALF: [&str; 2] = ["a", "b"];

fn cached(plan: &Plan, h: usize, f: u32) -> PathBuf {
    plan.cache
        .join(HALF[h])
        .join(format!("{}.exr", crate::report::frame_stem(f)))
}

/// How many (half, frame) images of the plan are not cached yet.
pub fn missing(plan: &Plan) -> usize {
    (0..2)
        .map(|h| {
            plan.numbers
                .iter()
                .filter(|&&f| !cached(plan, h, f).exists())
                .count()
        })
        .sum()
}

/// One half's frames, from the cache where present, else traced and cached.
fn half(plan: &Plan, h: usize, spp: u32, tick: &(dyn Fn() + Sync)) -> Result<Vec<Hdr>> {
    let cfg = &plan.cfg;
    let size = cfg.sequence.size;
    let folder = plan.cache.join(HALF[h]);
    crate::report::prepare_out_dir(&folder)?;
    let mut images: Vec<Option<Hdr>> = Vec::with_capacity(plan.numbers.len());
    for &f in &plan.numbers {
        let path = cached(plan, h, f);
        if !path.exists() {
            images.push(None);
            continue;
        }
        // A cached frame that cannot be read (cut short by a full disk or a kill) or is of
        // another size is traced again, with a note, in place of failing the comparison.
        let why = match Hdr::read(&path) {
            Ok(img) if (img.width, img.height) == (size.width, size.height) => {
                images.push(Some(img));
                continue;
            }
            Ok(img) => format!("it is {}x{}, not {size}", img.width, img.height),
            Err(e) => format!("{e:#}"),
        };
        eprintln!(
            "note: {}: the cached reference frame is unusable ({why}); tracing it again",
            path.display()
        );
        images.push(None);
    }
    let todo: Vec<u32> = plan
        .numbers
        .iter()
        .zip(&images)
        .filter(|(_, i)| i.is_none())
        .map(|(&f, _)| f)
        .collect();
    let seq = config::Sequence {
        seed: half_seed(cfg.sequence.seed, h),
        ..cfg.sequence.clone()
    };
    let mut traced = Vec::new();
    // Walked from the first frame, so that the frames traced now are the ones a trace of the
    // whole sequence gives (see `trace_walking`).
    let last = todo.last().copied();
    crate::commands::reference::trace_walking(
        &plan.scene,
        &seq,
        crate::reference::Sampling::spp(spp),
        plan.numbers
            .iter()
            .copied()
            .take_while(|&f| last.is_some_and(|l| f <= l)),
        &|f| todo.binary_search(&f).is_ok(),
        tick,
        &mut |f, _, img| {
            crate::report::write_frame(&folder, f, &img, cfg.render.exposure)?;
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

/// The spp-weighted mean of two halves.
pub fn mean_of_halves(a: &Hdr, b: &Hdr, spp: [u32; 2]) -> Hdr {
    let (wa, wb) = (spp[0] as f32, spp[1] as f32);
    a.zip_map(b, |x, y| (x * wa + y * wb) / (wa + wb))
}

/// The reference frames of the plan and their halves, from the cache where present, else
/// traced and cached.
pub fn load_or_render(plan: &Plan, tick: &(dyn Fn() + Sync)) -> Result<CachedReference> {
    let spp = halves(plan.cfg.spp);
    let a = half(plan, 0, spp[0], tick)?;
    let b = half(plan, 1, spp[1], tick)?;
    Ok(from_halves(a, b, spp))
}

/// The reference of two halves of `spp` samples a pixel.
pub fn from_halves(a: Vec<Hdr>, b: Vec<Hdr>, spp: [u32; 2]) -> CachedReference {
    let frames = a
        .iter()
        .zip(&b)
        .map(|(x, y)| mean_of_halves(x, y, spp))
        .collect();
    CachedReference {
        frames,
        halves: [a, b],
        spp,
    }
}

#[cfg(test)]
mod tests {
    use super::super::plan::dir;
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
        // Another --environment, another reference: sky, none, a map by its bytes.
        let with_environment = |spec: &str| {
            let mut c = config::Compare::default();
            c.sequence.environment = Some(spec.parse().unwrap());
            dir(&c, "cornell")
        };
        let map = a.join("sky.hdr");
        std::fs::write(&map, "first").unwrap();
        let m = map.to_str().unwrap();
        let sky = with_environment("sky");
        assert_ne!(sky, dir_of("cornell", 256));
        assert_ne!(sky, with_environment("none"));
        assert_eq!(sky, with_environment("sky"));
        let first = with_environment(m);
        assert_ne!(first, sky);
        std::fs::write(&map, "second").unwrap();
        assert_ne!(with_environment(m), first, "edited map");
        std::fs::remove_dir_all(&root).unwrap();
    }

    /// A cache written before the halves (one image a frame, in a folder named
    /// `..._seed<S>`) is never taken for the halves: the folder's name says how the spp were
    /// split, and an odd spp splits A = B + 1.
    #[test]
    fn the_cache_folder_names_the_halves() {
        let c = config::Compare {
            spp: 256,
            ..Default::default()
        };
        let d = dir(&c, "cornell");
        let name = d.file_name().unwrap().to_string_lossy().into_owned();
        assert!(
            name.ends_with("_256spp_24fps_seed1_halves128+128"),
            "{name}"
        );
        let old = name.trim_end_matches("_halves128+128");
        assert_ne!(name, old);
        assert_eq!(halves(5), [3, 2]);
        assert_eq!(halves(2), [1, 1]);
        // The halves' seeds differ from each other, from the seed, and from a neighbouring
        // seed's halves.
        let s = [
            half_seed(7, 0),
            half_seed(7, 1),
            half_seed(8, 0),
            half_seed(8, 1),
        ];
        for i in 0..4 {
            assert_ne!(s[i], 7);
            assert_ne!(s[i], 8);
            for j in 0..i {
                assert_ne!(s[i], s[j]);
            }
        }
    }
}
