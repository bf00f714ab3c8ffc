//! One resolve step: a render's settings, its scene and its adapter in, every budget the
//! renderer and the sampler use out ([`Resolved`]), chosen before anything is built and
//! recorded in `run.json`. What `0` (from the scene) means for each setting is here: the
//! emitter samples from the direct light's variance where the camera looks ([`light_samples`]),
//! the ISM points from what a VPL sees ([`ism_points`]), the interleave block from the VPL
//! count and the image's size ([`interleave_for`]), the distance clamp from the scene's size ([`clamp`]), the
//! adapter's caps on them.

use crate::config::Render;
use crate::gpu::RendererConfig;
use crate::scene::{Frame, Scene};
use crate::trace::{Next, Tracer};
use crate::vpl::sampler::SamplerParams;
use anyhow::{bail, Context, Result};
use serde::Serialize;

/// A render's settings resolved against its scene and adapter: nothing is left to choose.
#[derive(Clone, Debug, Serialize)]
pub struct Resolved {
    /// The GPU renderer's sizes and budgets.
    pub renderer: RendererConfig,
    /// The sampler's parameters, the distance clamp among them.
    pub sampler: SamplerParams,
    /// A classical method's solver settings (None for instant radiosity).
    pub radiosity: Option<crate::radiosity::RadiositySettings>,
    /// For instant radiosity without compensation paths given: the share of the emitters'
    /// light that meets a surface within the distance clamp of where it leaves them
    /// ([`crate::compensation::near_field_share`]), from which `--compensate auto` chooses.
    pub near_field: Option<f32>,
}

/// The share of the emitters' light within the distance clamp of them
/// ([`crate::compensation::near_field_share`]) from which `--compensate auto` compensates (and
/// `--compensate off` says what it leaves out): a tenth. A Cornell box sends 0 there, the white
/// furnace (whose walls emit) a few percent from its edges, the lamps of
/// `tests/gpu/thin_gap.rs` (1 cm to 0 under a ceiling) 43-46%.
pub const NEAR_FIELD_SHARE: f32 = 0.1;

/// The paths a pixel `--compensate auto` traces where the near field reaches
/// [`NEAR_FIELD_SHARE`]. On the gap sweep of `tests/gpu/thin_gap.rs` (seeds 1-4, 32x32, 1024
/// VPLs) 64 brings the mean bias within 5% at every gap, where 16 leaves +5% to +15% at 1 cm
/// and 1 mm (a few pixels' paths find the gap's mouth; docs/math.md section 2).
pub const AUTO_COMPENSATE: u32 = 64;

/// Compensation paths a pixel for `setting` given the scene's near-field share `near_field`
/// (None: a classical method, which takes none).
pub fn compensate(setting: crate::gpu::Compensate, near_field: Option<f32>) -> u32 {
    match (setting, near_field) {
        (_, None) => 0,
        (crate::gpu::Compensate::Paths(k), _) => k,
        (crate::gpu::Compensate::Auto, Some(s)) => {
            if s >= NEAR_FIELD_SHARE {
                AUTO_COMPENSATE
            } else {
                0
            }
        }
    }
}

/// Resolves `cfg` (validated) for `scene`, whose frame 0 is `frame0` traced by `tracer`, on an
/// adapter of `limits`.
pub fn resolve(
    cfg: &Render,
    scene: &Scene,
    frame0: &Frame,
    tracer: &Tracer,
    limits: &wgpu::Limits,
) -> Result<Resolved> {
    if let (Some(solver), Some(env)) = (cfg.method.solver(), &frame0.emitters.environment) {
        bail!(
            "`method` {}: the classical radiosity solvers do not take an environment's light (scene '{}' is lit by the environment {}); use `method` instant",
            solver.name(),
            scene.name,
            env.name
        );
    }
    let mut renderer = bounds(cfg, frame0.tris.len());
    // Within the adapter's shadow layers, 5 a sample, and irad's cap on a texture's bytes.
    let per_sample = crate::gpu::renderer::shadow_bytes(1, cfg.quality.shadow_size);
    let most = (limits.max_texture_array_layers / 5)
        .min((crate::gpu::renderer::MAX_TEXTURE_BYTES / per_sample) as u32)
        .max(1);
    renderer.light_samples = light_samples(cfg, frame0, tracer, most);
    let em = &frame0.emitters;
    let kinds: Vec<&str> = [
        (!em.tris.is_empty(), "emitting triangles"),
        (!em.lights.is_empty(), "punctual lights"),
        (em.environment.is_some(), "an environment"),
    ]
    .into_iter()
    .filter_map(|(has, what)| has.then_some(what))
    .collect();
    if kinds.len() > 1 && (renderer.light_samples as usize) < kinds.len() {
        bail!(
            "`light_samples` {}: scene '{}' has {}, which need at least {} samples (one for each)",
            renderer.light_samples,
            scene.name,
            kinds.join(" and "),
            kinds.len()
        );
    }
    renderer.ism_points = ism_points(cfg, frame0, tracer);
    renderer.num_points = ism_point_set_size(renderer.ism_points, frame0.tris.len());
    let sampler = sampler_params(cfg, frame0, tracer);
    let near_field = (cfg.method.solver().is_none()
        && matches!(
            cfg.quality.compensate,
            crate::gpu::Compensate::Auto | crate::gpu::Compensate::Paths(0)
        ))
    .then(|| crate::compensation::near_field_share(frame0, tracer, sampler.clamp));
    // (A count given leaves the share unmeasured; a classical method takes none.)
    renderer.compensate = compensate(
        cfg.quality.compensate,
        cfg.method
            .solver()
            .is_none()
            .then(|| near_field.unwrap_or(0.0)),
    );
    Ok(Resolved {
        renderer,
        sampler,
        near_field,
        radiosity: match cfg.method.solver() {
            Some(solver) => {
                let s = radiosity_settings(cfg, solver, scene);
                s.validate()
                    .with_context(|| format!("scene '{}'", scene.name))?;
                Some(s)
            }
            None => None,
        },
    })
}

/// The relative variance of the direct light's N-sample estimate that `--light-samples 0`
/// aims at: a relative standard error of 5% a pixel.
pub const DIRECT_REL_VAR: f32 = 0.05 * 0.05;
/// A classical method's target: half [`DIRECT_REL_VAR`], so about twice the samples. Its
/// image is a still solution; what moves as the camera does is how the pixels sample the
/// emitter samples' hard shadows, whose steps are 1/N of the light. On `cornell-orbit` (96x96,
/// 24 frames, seed 4, against an 8192-spp reference), 48 samples instead of 24 take progressive
/// refinement's own warped flicker from 0.000173 to 0.000147 (docs/radiosity.md).
pub const CLASSICAL_DIRECT_REL_VAR: f32 = DIRECT_REL_VAR / 2.0;
/// The range of `--light-samples 0`'s choice.
pub const AUTO_LIGHT_SAMPLES: (u32, u32) = (4, 64);

/// Emitter samples for a scene from the relative squared error of its direct light at each
/// sample count (`errors`: (N, error) by increasing N, from
/// `reference::twin::direct_relative_error` over what the camera sees): the fewest that reach
/// `target` ([`DIRECT_REL_VAR`], or [`CLASSICAL_DIRECT_REL_VAR`]), else the most of them;
/// within [`AUTO_LIGHT_SAMPLES`] and never fewer than `exact` (the slots the scene's punctual
/// lights take, plus one if it has emitter triangles).
pub fn light_samples_for(errors: &[(u32, f32)], target: f32, exact: u32) -> u32 {
    let (lo, hi) = AUTO_LIGHT_SAMPLES;
    let n = errors
        .iter()
        .find(|&&(_, e)| e <= target)
        .or(errors.last())
        .map_or(lo, |&(n, _)| n);
    n.clamp(lo, hi).max(exact)
}

/// Sub-samples per pixel side: `--aa`, or (0) from the method: 2 for instant radiosity, 4 for
/// a classical method. A classical method shows a view-independent solution, still from frame
/// to frame, so what moves in its image is where the pixel grid samples it: its shadows' and
/// shading's steps inside surfaces, in the sub-samples' `1 / aa^2` steps. On `cornell-orbit`
/// (96x96, 24 frames, against an 8192-spp reference) 4x4 sub-samples take the warped flicker's
/// excess over the reference's floor inside surfaces from 0.000019 to 0.000007
/// (docs/antialiasing.md).
///
/// The classical methods' 4 comes down (not below 2) where the sub-sampled frame would pass
/// 8192 texels a side, the texture size every adapter offers (`--size 2560x1440` gets 3).
pub fn aa(cfg: &Render) -> u32 {
    let side = cfg.sequence.size.width.max(cfg.sequence.size.height).max(1);
    match (cfg.quality.aa, cfg.method.solver()) {
        (0, None) => 2,
        (0, Some(_)) => (8192 / side).clamp(2, 4),
        (n, _) => n,
    }
}

/// Pixel-VPL pairs a frame's gather evaluates in full before `--interleave 0` interleaves it:
/// 2^23, about 20 ms on this project's 2-core llvmpipe (the full gather of 64x64 sub-samples and
/// 1024 VPLs, 2^22 pairs, takes 10 ms there) and well under a millisecond on a GPU.
pub const GATHER_PAIRS: u64 = 1 << 23;

/// `--interleave 0`'s block side for `vpls` VPLs over `sub_pixels` sub-samples (the pixels
/// times `aa^2`): the smallest of 1, 2, 4 (8 from 4096 VPLs) that keeps the gather within
/// [`GATHER_PAIRS`] pixel-VPL pairs, or the largest. Interleaving is a trade of the gather's
/// time for error: its filter averages each block's subsets back over a block that, in a
/// small image, spans much of what the image shows. Where the full gather costs no more than
/// the budget it is not made. Measured: on the 1 cm gap's box at 32x32 with 1024 VPLs (2^22
/// pairs), a 4x4 block against none takes the relMSE against 16 references from 0.040 to 0.034
/// (`mh`, mean of seeds 1-8; largest 0.061 to 0.049). At the largest side, on `cornell-orbit`
/// at 256x256 (`git show 38ba47d:README.md`, "Speed against Mitsuba 3"): frames alone, 8
/// against 4 raises relMSE 9% at 256 VPLs and 8% at 1024 but 2% at 4096, where it takes the
/// gather from 320 ms to 70 ms a frame on lavapipe.
pub fn interleave_for(vpls: u32, sub_pixels: u64) -> u32 {
    let most = if vpls >= 4096 { 8 } else { 4 };
    let pairs = sub_pixels.saturating_mul(vpls as u64);
    let mut n = 1;
    while n < most && pairs > GATHER_PAIRS * (n * n) as u64 {
        n *= 2;
    }
    n
}

/// The range of `--ism-points 0`'s choice.
pub const AUTO_ISM_POINTS: (u32, u32) = (64, 4096);

/// Points a VPL splats for tiles of `ism_size` texels whose holes `pull_levels` levels of
/// pull-push fill, in a scene of `triangles` triangles of whose surface area a VPL sees the
/// fraction `seen` (in front of it, unoccluded; `vpl::ism_points::seen_fraction`), the larger of:
/// - coverage: enough that the points it sees alone fall in every texel of the tile's disk
///   at the coarsest level, n ln n of them for its n texels (the coupon collector's
///   expectation), so that pull-push closes the tile without the near-field points (64
///   texels and 3 levels: 197 / `seen`);
/// - detail: one for every [`TRIANGLES_PER_ISM_POINT`] triangles. Geometry finer than the
///   near-field rays' cells (a column, a lamp) is in a tile only through points of the set.
///   Measured: on the atrium (128k triangles then, 256 VPLs) relMSE against the path tracer falls
///   from 0.093 at 823 points to 0.087 at 4096, and at 1024 VPLs from 0.053 at 1001 to 0.050;
///   on the Cornell box (36) it stays within 1% from 64 to 4096 points, where the near-field
///   points carry its few large surfaces.
///
/// Within [`AUTO_ISM_POINTS`].
pub fn ism_points_for(ism_size: u32, pull_levels: u32, seen: f32, triangles: usize) -> u32 {
    let levels = crate::vpl::ism_points::pull_levels_run(ism_size, pull_levels);
    let side = (ism_size >> levels) as f32;
    let n = (std::f32::consts::FRAC_PI_4 * side * side).max(1.0);
    let coverage = (n * n.ln().max(1.0) / seen.max(1e-3)).ceil() as u32;
    let detail = triangles
        .div_ceil(TRIANGLES_PER_ISM_POINT)
        .min(u32::MAX as usize) as u32;
    let (lo, hi) = AUTO_ISM_POINTS;
    coverage.max(detail).clamp(lo, hi)
}

/// `--ism-points 0`'s detail term: a point a slot for every this many triangles.
pub const TRIANGLES_PER_ISM_POINT: usize = 32;

/// Points in the ISM point set of a scene of `triangles` triangles for `ism_points` points
/// a slot: 16 slots' worth or one a triangle, whichever is more (a point set smaller than the
/// triangle count leaves small triangles, a column's facets, with no point in any tile),
/// between 2^16 and 2^22, and never fewer than one slot's.
pub fn ism_point_set_size(ism_points: u32, triangles: usize) -> u32 {
    ism_points
        .saturating_mul(16)
        .max(triangles.min(u32::MAX as usize) as u32)
        .clamp(1 << 16, 1 << 22)
        .max(ism_points)
}

/// The GPU renderer's sizes before the scene is seen, for checking a render's settings
/// against an adapter before anything is built (`irad compare` checks every run so): each
/// choice left to the scene at its most demanding bound (the most ISM points, the fewest
/// light samples). Nothing is built from it: [`resolve`] chooses.
pub fn bounds(cfg: &Render, triangles: usize) -> RendererConfig {
    let q = &cfg.quality;
    // From the scene: [`resolve`] chooses ([`ism_points`]); the most it can choose stands in
    // for the checks.
    let points = match q.ism_points {
        0 => AUTO_ISM_POINTS.1,
        n => n,
    };
    RendererConfig {
        width: cfg.sequence.size.width,
        height: cfg.sequence.size.height,
        slots: cfg.vpls,
        ism_size: q.ism_size,
        ism_points: points,
        num_points: ism_point_set_size(points, triangles),
        pull_levels: q.pull_levels,
        ism_bias: q.ism_bias,
        // From the scene: [`resolve`] chooses ([`light_samples`], within the adapter's
        // limit); the fewest it can choose stand in for the checks.
        light_samples: if q.light_samples == 0 {
            AUTO_LIGHT_SAMPLES.0
        } else {
            q.light_samples
        },
        shadow_size: q.shadow_size,
        interleave: match q.interleave {
            0 => {
                let (w, h, aa) = (cfg.sequence.size.width, cfg.sequence.size.height, aa(cfg));
                interleave_for(cfg.vpls, w as u64 * h as u64 * (aa * aa) as u64)
            }
            n => n,
        },
        aa: aa(cfg),
        split_light_samples: cfg.method.solver().is_none(),
        edge_rays: q.edge_rays,
        // From the scene's near field for `auto` ([`resolve`], [`compensate`]).
        compensate: match q.compensate {
            crate::gpu::Compensate::Paths(k) => k,
            crate::gpu::Compensate::Auto => 0,
        },
        accumulate: q.accumulate,
        history: q.history,
        shadow_bias: 1.5,
        exposure: cfg.exposure,
        seed: cfg.sequence.seed,
    }
}

/// Points a VPL splats: `--ism-points`, or (0) from the scene at frame 0 (`frame0`,
/// traced by `tracer`) by [`ism_points_for`] from the fraction of its area a VPL sees and
/// its triangles.
pub fn ism_points(cfg: &Render, frame0: &Frame, tracer: &Tracer) -> u32 {
    if cfg.quality.ism_points > 0 {
        return cfg.quality.ism_points;
    }
    let seen = crate::gpu::ism::seen_fraction(frame0, tracer, cfg.sequence.seed);
    let q = &cfg.quality;
    ism_points_for(q.ism_size, q.pull_levels, seen, frame0.tris.len())
}

/// Emitter samples for the sequence: `--light-samples` (checked against the adapter by
/// the renderer), or (0) from the scene at frame 0 (`frame0`, traced by `tracer`) as the
/// camera sees it at 64 pixel centres across (in the image's aspect), by
/// [`light_samples_for`], at most `most` (what the adapter can hold).
pub fn light_samples(cfg: &Render, frame0: &Frame, tracer: &Tracer, most: u32) -> u32 {
    if cfg.quality.light_samples > 0 {
        return cfg.quality.light_samples;
    }
    let seed = cfg.sequence.seed ^ 0x11647;
    // The punctual lights take their slots first (`Frame::emitter_samples`): 256 area
    // samples after them, so that each of up to 64 strata holds 4 or more.
    let punctual =
        |s: &[crate::scene::EmitterSample]| s.iter().filter(|l| !l.kind.is_sampled()).count();
    let exact = punctual(&frame0.emitter_samples(seed, 256));
    let samples = frame0.emitter_samples(seed, 256 + exact);
    let area = samples.iter().any(|l| l.kind.is_sampled());
    let size = &cfg.sequence.size;
    let rows = (64 * size.height).div_ceil(size.width.max(1)).clamp(1, 256);
    let points = crate::reference::twin::pixel_points(frame0, tracer, 64, rows);
    let (lo, hi) = AUTO_LIGHT_SAMPLES;
    // N samples in all leave N - exact for the area emitters.
    let counts: Vec<u32> = (lo..=hi).filter(|&n| !area || n as usize > exact).collect();
    let area_counts: Vec<u32> = counts
        .iter()
        .map(|&n| (n as usize).saturating_sub(exact).max(1) as u32)
        .collect();
    let errors = crate::reference::twin::direct_relative_error(
        frame0,
        tracer,
        &points,
        &samples,
        &area_counts,
    );
    let pairs: Vec<(u32, f32)> = counts.into_iter().zip(errors).collect();
    let target = match cfg.method.solver() {
        Some(_) => CLASSICAL_DIRECT_REL_VAR,
        None => DIRECT_REL_VAR,
    };
    light_samples_for(&pairs, target, exact as u32 + area as u32).min(most)
}

/// The distance clamp for `frame0` (a scene's frame 0, traced by `tracer`): `--clamp`, or
/// [`CLAMP_OF_FREE_PATH`] times its mean free path ([`free_path`]); 2% of its bounding-box
/// diagonal where no surface sees another.
pub fn clamp(cfg: &Render, frame0: &Frame, tracer: &Tracer) -> f32 {
    cfg.clamp
        .unwrap_or_else(|| match free_path(frame0, tracer) {
            Some(d) => CLAMP_OF_FREE_PATH * d,
            None => {
                let (lo, hi) = frame0.bounds();
                0.02 * (hi - lo).length()
            }
        })
}

/// The default distance clamp as a fraction of the scene's mean free path: 0.0693 in the
/// Cornell box, where the rule before (2% of the bounding-box diagonal) gave 0.0694.
pub const CLAMP_OF_FREE_PATH: f32 = 1.0 / 14.0;

/// Points [`free_path`] starts its rays from.
const FREE_PATH_POINTS: usize = 8192;

/// The scene's mean free path, the length its feature size is measured in (docs/math.md,
/// section 4): from 8192 points on its surfaces (by area), a cosine-distributed ray on each
/// side a receiver sees (the front only of single-sided triangles), and the mean distance to
/// what those that hit something hit, but not from inside a closed mesh (4V/S in a closed
/// convex room). It is how far a VPL's
/// light travels to the next surface, so it follows the spaces light fills, neither where the
/// scene sits nor the empty space around it (a far small object adds little area, and rays
/// that leave the scene are not counted). None when fewer than 16 rays hit (no surface sees
/// another). Deterministic; linear in the scene's scale up to float rounding.
pub fn free_path(frame: &Frame, tracer: &Tracer) -> Option<f32> {
    let mut cdf = Vec::with_capacity(frame.areas.len());
    let mut acc = 0.0f64;
    for &a in &frame.areas {
        acc += a as f64;
        cdf.push(acc);
    }
    let cutouts = frame.has_cutouts();
    let mut d: Vec<f32> = Vec::with_capacity(2 * FREE_PATH_POINTS);
    // A Hammersley-Halton set: the area stratified ((i + 0.382) / N: off the simple fractions
    // at which the triangles of equal areas meet, where rounding would choose between two),
    // the point on its triangle and the two rays' directions from radical inverses.
    const GOLDEN: f64 = 0.381_966_011_250_105_1;
    for i in 0..FREE_PATH_POINTS {
        let u = (i as f64 + GOLDEN) / FREE_PATH_POINTS as f64 * acc;
        let tri = cdf.partition_point(|&c| c <= u).min(cdf.len() - 1);
        // Rotated by irrational shifts (Cranley-Patterson), off the rational points and
        // axis-aligned directions that meet a scene's edges exactly.
        let r = |base: u32| (radical_inverse(i as u32, base) + base as f32 * GOLDEN as f32).fract();
        let b = crate::math::triangle_barycentrics(glam::Vec2::new(r(2), r(3)));
        if cutouts && frame.cut_at(tri, b.x, b.y) {
            continue;
        }
        let x = frame.point(tri, b.x, b.y);
        let n = frame.normals[tri];
        let dirs = [
            (n, glam::Vec2::new(r(5), r(7))),
            (-n, glam::Vec2::new(r(11), r(13))),
        ];
        for (side, u) in dirs {
            if side != n && tracer.single_sided(tri as u32) {
                continue;
            }
            let dir = crate::math::cosine_hemisphere(side, u);
            // Not into a gap thinner than the tracer resolves, nor inside closed meshes,
            // where no light the frame shows goes.
            if let Next::Hit(h) = tracer.follow(&tracer.leave(x, n, dir), f32::INFINITY) {
                if !tracer.struck_inside_solid(h.tri, frame.normals[h.tri as usize], dir) {
                    d.push(h.t);
                }
            }
        }
    }
    if d.len() < 16 {
        return None;
    }
    Some((d.iter().map(|&x| x as f64).sum::<f64>() / d.len() as f64) as f32)
}

/// The classical solver's settings for `scene` (element size from its size).
pub fn radiosity_settings(
    cfg: &Render,
    solver: crate::radiosity::Solver,
    scene: &Scene,
) -> crate::radiosity::RadiositySettings {
    let (lo, hi) = scene.at(0.0).bounds();
    crate::radiosity::RadiositySettings {
        solver,
        meshing: cfg.meshing,
        // 0.15 in the Cornell box, whose bounding-box diagonal is 3.46.
        element_size: 0.0433 * (hi - lo).length(),
        seed: cfg.sequence.seed,
        ..Default::default()
    }
}

/// The radical inverse of `i` in `base`, in [0, 1).
fn radical_inverse(mut i: u32, base: u32) -> f32 {
    let (mut inv, mut f) = (0.0f64, 1.0 / base as f64);
    while i > 0 {
        inv += (i % base) as f64 * f;
        i /= base;
        f /= base as f64;
    }
    (inv as f32).min(1.0 - f32::EPSILON / 2.0)
}

/// The sampler's parameters for `scene`, whose frame 0 is `frame0` traced by `tracer`.
pub fn sampler_params(cfg: &Render, frame0: &Frame, tracer: &Tracer) -> SamplerParams {
    let s = &cfg.sampler;
    SamplerParams {
        kind: s.kind,
        slots: cfg.vpls as usize,
        candidates: s.candidates(cfg.vpls) as usize,
        knobs: s.knobs.clone(),
        clamp: clamp(cfg, frame0, tracer),
        seed: cfg.sequence.seed,
        width: cfg.sequence.size.width,
        height: cfg.sequence.size.height,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `--compensate auto` (the default) traces [`AUTO_COMPENSATE`] paths a pixel from a near
    /// field of [`NEAR_FIELD_SHARE`] on and none below it or for a classical method; a count
    /// given is kept, `off` is none; the flag reads and writes the three forms.
    #[test]
    fn compensation_follows_the_near_field() {
        use crate::gpu::Compensate::{self, Auto, Paths};
        assert_eq!(compensate(Auto, Some(0.0)), 0);
        assert_eq!(compensate(Auto, Some(NEAR_FIELD_SHARE * 0.99)), 0);
        assert_eq!(compensate(Auto, Some(NEAR_FIELD_SHARE)), 64);
        assert_eq!(compensate(Auto, Some(0.45)), 64);
        assert_eq!(compensate(Auto, None), 0);
        assert_eq!(compensate(Paths(16), Some(0.0)), 16);
        assert_eq!(compensate(Paths(0), Some(0.45)), 0);
        assert_eq!(compensate(Paths(16), None), 0);
        for (text, value) in [
            ("auto", Auto),
            ("off", Paths(0)),
            ("0", Paths(0)),
            ("16", Paths(16)),
        ] {
            assert_eq!(text.parse::<Compensate>(), Ok(value), "{text}");
        }
        assert_eq!(Paths(16).to_string(), "16");
        assert_eq!(Paths(0).to_string(), "off");
        assert_eq!(Auto.to_string(), "auto");
        assert!("16x".parse::<Compensate>().is_err());
        assert_eq!(crate::gpu::Quality::default().compensate, Auto);
    }

    /// `--aa 0` (the default) is 2x2 for instant radiosity and 4x4 for the classical methods;
    /// an explicit count is kept.
    #[test]
    fn aa_follows_the_method() {
        use crate::config::{Method, Render};
        let mut r = Render::default();
        assert_eq!(r.quality.aa, 0);
        assert_eq!(aa(&r), 2);
        for m in [
            Method::Progressive,
            Method::Hierarchical,
            Method::Stochastic,
        ] {
            r.method = m;
            assert_eq!(aa(&r), 4);
        }
        r.sequence.size.width = 2560;
        assert_eq!(aa(&r), 3);
        r.sequence.size.width = 7680;
        assert_eq!(aa(&r), 2);
        r.quality.aa = 3;
        assert_eq!(aa(&r), 3);
        r.method = Method::Instant;
        assert_eq!(aa(&r), 3);
    }

    #[test]
    fn light_samples_follow_the_direct_lights_variance() {
        // The fewest samples whose error is at most 0.0025, else the most tried.
        let errs =
            |relvar: f32| -> Vec<(u32, f32)> { (4..=64).map(|n| (n, relvar / n as f32)).collect() };
        let v = DIRECT_REL_VAR;
        assert_eq!(light_samples_for(&errs(0.074), v, 1), 30);
        assert_eq!(light_samples_for(&errs(0.024), v, 1), 10);
        assert_eq!(light_samples_for(&errs(0.0), v, 1), 4);
        assert_eq!(light_samples_for(&errs(50.0), v, 1), 64);
        assert_eq!(light_samples_for(&[], v, 1), 4);
        // A classical method's target: twice the samples.
        assert_eq!(
            light_samples_for(&errs(0.074), CLASSICAL_DIRECT_REL_VAR, 1),
            60
        );
        assert_eq!(
            light_samples_for(&errs(0.5), CLASSICAL_DIRECT_REL_VAR, 1),
            64
        );
        // Never fewer than the exact (punctual) slots.
        assert_eq!(light_samples_for(&errs(0.0), v, 7), 7);
        assert_eq!(light_samples_for(&errs(50.0), v, 80), 80);
        // An explicit --light-samples is kept; 0 chooses from the scene.
        let scene = crate::scene::builtin::load("cornell").unwrap().unwrap();
        let f = scene.at(0.0);
        let tracer = crate::trace::Tracer::new(&f);
        let mut r = Render::default();
        r.quality.light_samples = 12;
        assert_eq!(light_samples(&r, &f, &tracer, 8), 12);
        r.quality.light_samples = 0;
        let n = light_samples(&r, &f, &tracer, 409);
        assert!((26..=34).contains(&n), "the Cornell box chose {n}");
        // A classical method about twice as many (measured 51 against 26).
        r.method = crate::config::Method::Progressive;
        let c = light_samples(&r, &f, &tracer, 409);
        assert!(
            (2 * n - 4..=2 * n + 4).contains(&c),
            "the Cornell box chose {c} for a classical method, {n} for instant radiosity"
        );
        r.method = crate::config::Method::Instant;
        // The adapter's limit caps the choice.
        assert_eq!(light_samples(&r, &f, &tracer, 8), 8);
    }

    #[test]
    fn ism_points_follow_what_a_vpl_sees() {
        // 64 texels, 3 levels: the 8x8 coarsest level's disk, n = 16 pi = 50.3 texels, needs
        // n ln n = 197 points seen; a VPL that sees a tenth of the scene splats 10 times that.
        assert_eq!(ism_points_for(64, 3, 1.0, 36), 197);
        assert_eq!(ism_points_for(64, 3, 0.1, 36), 1970);
        // Many triangles: one point for every 32 of them, where that is more.
        assert_eq!(ism_points_for(64, 3, 0.24, 128_060), 4002);
        assert_eq!(ism_points_for(64, 3, 0.1, 32_000), 1970);
        // Fewer levels: a finer coarsest level (16x16 of 64: 201 texels, 201 ln 201 = 1066.4; or
        // 8x8 with none of 8).
        assert_eq!(ism_points_for(64, 2, 1.0, 36), 1067);
        assert_eq!(ism_points_for(8, 0, 1.0, 36), 197);
        // Bounded both ways (2x2 at the coarsest level needs no more than the fewest).
        assert_eq!(ism_points_for(8, 3, 1.0, 36), 64);
        assert_eq!(ism_points_for(64, 3, 0.0, 36), 4096);
        assert_eq!(ism_points_for(64, 3, 1.0, 1 << 20), 4096);
        // What a VPL sees: inside an empty cube, the 5 faces other than its own (5/6 of the
        // area; 4096 pairs: standard error 0.006).
        let seen = |name: &str| {
            let scene = crate::scene::builtin::load(name).unwrap().unwrap();
            let f = scene.at(0.0);
            crate::vpl::ism_points::seen_fraction(&f, &crate::trace::Tracer::new(&f), 1)
        };
        let furnace = seen("furnace");
        assert!((furnace - 5.0 / 6.0).abs() < 0.025, "furnace: {furnace}");
        // The Cornell box's two blocks, large for its room, hide much of it (measured 0.42),
        // the atrium's columns and gallery more (0.24): a tracer that missed occluders
        // would give them the furnace's.
        let (cornell, atrium) = (seen("cornell"), seen("atrium"));
        println!("seen: furnace {furnace}, cornell {cornell}, atrium {atrium}");
        assert!(cornell < furnace - 0.25, "cornell: {cornell}");
        assert!(atrium < cornell - 0.1, "atrium: {atrium}");
        // An explicit --ism-points is kept; 0 chooses from the scene.
        let scene = crate::scene::builtin::load("cornell").unwrap().unwrap();
        let f = scene.at(0.0);
        let tracer = crate::trace::Tracer::new(&f);
        let mut r = Render::default();
        r.quality.ism_points = 1000;
        assert_eq!(ism_points(&r, &f, &tracer), 1000);
        r.quality.ism_points = 0;
        assert_eq!(
            ism_points(&r, &f, &tracer),
            ism_points_for(64, 3, seen("cornell"), 36)
        );
    }

    #[test]
    fn the_ism_point_set_grows_with_the_triangles() {
        // The Cornell box (36 triangles) keeps 16 slots' worth of 4096 points.
        assert_eq!(ism_point_set_size(4096, 36), 1 << 16);
        assert_eq!(ism_point_set_size(8192, 36), 1 << 17);
        // The atrium: one point a triangle, more than 16 slots' worth.
        assert_eq!(ism_point_set_size(4096, 128_060), 128_060);
        // Bounded both ways, and never below one slot's points.
        assert_eq!(ism_point_set_size(4096, 50_000_000), 1 << 22);
        assert_eq!(ism_point_set_size(1, 0), 1 << 16);
        assert_eq!(ism_point_set_size(1 << 23, 0), 1 << 23);
    }

    #[test]
    fn the_default_clamp_is_a_fourteenth_of_the_mean_free_path() {
        let of = |name: &str| {
            let scene = crate::scene::builtin::load(name).unwrap().unwrap();
            let f = scene.at(0.0);
            let t = Tracer::new(&f);
            (
                free_path(&f, &t).unwrap(),
                clamp(&Render::default(), &f, &t),
            )
        };
        // In a closed convex room the mean free path is 4V/S (Cauchy): 4/3 in the empty
        // cube of side 2 (measured 1.3313).
        let (furnace, _) = of("furnace");
        assert!((furnace - 4.0 / 3.0).abs() < 0.01, "furnace: {furnace}");
        // The Cornell box's blocks shorten it (measured 0.9704): its clamp stays the 0.069 of
        // the rule before (2% of its bounding-box diagonal, 0.0694).
        let (cornell, c) = of("cornell");
        assert!((cornell - 0.970).abs() < 0.005, "cornell: {cornell}");
        assert!((c - 0.0694).abs() < 0.0005, "cornell's clamp: {c}");
        // An explicit clamp is kept.
        let scene = crate::scene::builtin::load("cornell").unwrap().unwrap();
        let f = scene.at(0.0);
        let r = Render {
            clamp: Some(0.25),
            ..Default::default()
        };
        assert_eq!(clamp(&r, &f, &Tracer::new(&f)), 0.25);
    }

    #[test]
    fn interleave_zero_chooses_from_the_vpl_count_and_the_size() {
        // 256x256 (the default) with 2x2 sub-samples: the largest block.
        let mut r = Render::default();
        assert_eq!(r.sequence.size.width, 256);
        assert_eq!(bounds(&r, 36).interleave, 4);
        r.vpls = 4096;
        assert_eq!(bounds(&r, 36).interleave, 8);
        r.quality.interleave = 2;
        assert_eq!(bounds(&r, 36).interleave, 2, "--interleave 2 is kept");
        // Small images: the thin-gap sweep's 32x32 and 1024 VPLs (2^22 pairs) are gathered in
        // full; 64x64 (2^24) in 2x2 blocks; 128x128 in 4x4.
        r.quality.interleave = 0;
        r.vpls = 1024;
        for (side, want) in [(32, 1), (64, 2), (128, 4), (1920, 4)] {
            r.sequence.size = crate::config::Size {
                width: side,
                height: side,
            };
            assert_eq!(bounds(&r, 36).interleave, want, "{side}x{side}");
        }
        // Over sizes and VPL counts: the smallest block that keeps the gather within the
        // budget, never above 4 (8 from 4096 VPLs), and never smaller in a larger image.
        for vpls in [1, 64, 256, 1024, 4095, 4096, 65536] {
            let most = if vpls >= 4096 { 8 } else { 4 };
            let mut last = 1;
            for side in [1u64, 8, 16, 32, 45, 64, 100, 128, 256, 1080, 4096, 1 << 20] {
                let px = side * side * 4;
                let n = interleave_for(vpls, px);
                assert!(
                    [1, 2, 4, 8].contains(&n) && n <= most,
                    "{vpls} VPLs, {side}: {n}"
                );
                assert!(
                    n >= last,
                    "{vpls} VPLs: {side} gets {n}, smaller than {last}"
                );
                let pairs = px as u128 * vpls as u128;
                let within = |n: u32| pairs <= GATHER_PAIRS as u128 * (n * n) as u128;
                assert!(
                    n == most || within(n),
                    "{vpls} VPLs, {side}: {n} over the budget"
                );
                assert!(
                    n == 1 || !within(n / 2),
                    "{vpls} VPLs, {side}: {n} not the smallest"
                );
                last = n;
            }
        }
    }
}
