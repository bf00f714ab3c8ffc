//! One frame, in order (DESIGN.md "One frame, in order"): the whole flow in [`Pipeline::render_frame`].

use crate::config;
use crate::gpu::radiosity::RadiosityPass;
use crate::gpu::{Gpu, GpuFrame, RenderedImage, Renderer};
use crate::radiosity;
use crate::scene::Scene;
use crate::trace::Tracer;
pub use crate::vpl::sampler::SamplerKind;
use crate::vpl::sampler::{Sampler, SamplerParams, Selection};
use anyhow::Result;
use std::sync::Arc;
use std::time::Instant;

/// Records the seconds since `t` as stage `name` and restarts `t`.
fn lap(stages: &mut Vec<(&'static str, f64)>, name: &'static str, t: &mut Instant) {
    stages.push((name, t.elapsed().as_secs_f64()));
    *t = Instant::now();
}

/// What rendering frame index `index` gave: the image and the frame's record.
pub struct FrameOutput {
    pub index: u32,
    pub time: f32,
    pub image: RenderedImage,
    pub selection: Selection,
    /// Seconds per stage, CPU stages then GPU passes, in order.
    pub stages: Vec<(&'static str, f64)>,
    pub seconds: f64,
    /// A classical method's solver: whether this frame solved (else it reused the last
    /// solution); None for instant radiosity.
    pub solved: Option<bool>,
    /// The solve's figures (elements, discontinuity lines, rays, seconds), in the frame that
    /// solved.
    pub radiosity: Option<radiosity::Stats>,
}

/// The renderer of one sequence: scene, ray tracer, sampler state and GPU passes, on a
/// device it shares with the process's other pipelines.
pub struct Pipeline {
    pub scene: Scene,
    /// A classical radiosity method's solver state, when `--method` names one.
    classical: Option<Classical>,
    /// The sampler's parameters (seed, distance clamp, sizes) for this scene.
    pub params: SamplerParams,
    pub fps: f32,
    pub renderer: Renderer,
    tracer: Tracer,
    sampler: Sampler,
    /// The light's temporal gradient between frames (`--accumulate` with `--history gradient`).
    gradient: crate::vpl::gradient::LightGradient,
    /// The last frame's emitter samples: the gradient is measured only when they or a vertex
    /// moved.
    last_lights: Vec<crate::scene::EmitterSample>,
}

/// Prints `note` on stderr unless this process printed it already (a compare builds a pipeline
/// for each run).
fn note_once(note: String) {
    static SEEN: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
    let mut seen = SEEN.lock().unwrap_or_else(|e| e.into_inner());
    if !seen.contains(&note) {
        eprintln!("{note}");
        seen.push(note);
    }
}

impl Pipeline {
    /// Checks `cfg` (against the adapter too) and builds the pipeline for `scene` on `gpu`.
    pub fn new(gpu: Arc<Gpu>, scene: Scene, cfg: &config::Render) -> Result<Pipeline> {
        cfg.validate()?;
        let frame0 = scene.at(0.0);
        let tracer = Tracer::new(&frame0);
        let resolved = crate::resolve::resolve(cfg, &scene, &frame0, &tracer, &gpu.limits)?;
        let mut renderer = Renderer::new(gpu, resolved.renderer, &frame0)?;
        renderer.profiling = cfg.profiling.on(&renderer.gpu);
        renderer.reuse = !cfg.no_reuse;
        renderer.cull = !cfg.no_cull;
        let params = resolved.sampler;
        if let Some(share) = resolved
            .near_field
            .filter(|&s| s >= crate::resolve::NEAR_FIELD_SHARE)
        {
            let what = match renderer.config.compensate {
                0 => "the clamp darkens what lies that near; --compensate auto gives it back"
                    .to_owned(),
                k => {
                    format!("compensating the clamp with {k} paths a pixel (--compensate off: not)")
                }
            };
            note_once(format!(
                "note: scene '{}': {:.0}% of its emitters' light meets a surface within the distance clamp ({:.3}) of where it leaves them (a lamp under a ceiling, against a wall): {what} (docs/math.md, section 4)",
                scene.name,
                100.0 * share,
                params.clamp
            ));
        }
        let sampler = Sampler::new(params.clone());
        let classical = resolved.radiosity.map(|settings| Classical {
            settings,
            cache: radiosity::Cache::default(),
            progress: Box::new(|_| {}),
            // The same sub-samples per pixel as the frame it adds to (checked against the
            // adapter with the renderer's).
            pass: RadiosityPass::with_aa(
                &renderer.gpu,
                cfg.sequence.size.width,
                cfg.sequence.size.height,
                renderer.config.aa,
            ),
            edges: None,
        });
        Ok(Pipeline {
            classical,
            scene,
            params,
            fps: cfg.sequence.fps,
            renderer,
            tracer,
            sampler,
            gradient: Default::default(),
            last_lights: Vec::new(),
        })
    }

    /// Sets what a classical method's solve tells how far it has got (nothing by default).
    pub fn on_solve_progress(
        &mut self,
        progress: impl Fn(&radiosity::SolveProgress) + Send + Sync + 'static,
    ) {
        if let Some(c) = &mut self.classical {
            c.progress = Box::new(progress);
        }
    }

    /// Renders frame index `f` (the scene at time f / fps). With `components`, the direct and
    /// indirect images come back too.
    pub fn render_frame(&mut self, f: u32, components: bool) -> Result<FrameOutput> {
        self.render_at(f, (f as f64 / self.fps as f64) as f32, components)
    }

    /// Renders the scene at `time` seconds as the sequence's frame index `f` (what the
    /// sampler's state and random streams follow): an interactive view keeps drawing frames
    /// f, f+1, ... while its time stands still.
    pub fn render_at(&mut self, f: u32, time: f32, components: bool) -> Result<FrameOutput> {
        let s = &self.params;
        let start = Instant::now();
        let mut stages = Vec::new();
        let mut t = Instant::now();
        // 1. The scene at time t.
        let mut frame = self.scene.at(time);
        lap(&mut stages, "scene", &mut t);
        // 2. Ray tracing: rebuild the BVH only if the geometry moved.
        let moved = self.tracer.update(&frame);
        // Light from inside a closed lamp reaches nothing the frame shows: paths and emitter
        // samples start only where it gets out (trace::solids).
        self.tracer.keep_lit_emitters(&mut frame);
        lap(&mut stages, "bvh", &mut t);
        // 3-6. Camera points, light paths, importance and the sampler: the frame's VPLs and
        // their weights (none for a classical method: its solution gives the indirect light).
        let selection = if self.classical.is_some() {
            Selection::default()
        } else {
            self.sampler.select(&frame, &self.tracer, f as u64)
        };
        if self.classical.is_none() {
            stages.push(("importance", selection.importance_s));
            stages.push(("vpls", t.elapsed().as_secs_f64() - selection.importance_s));
        }
        t = Instant::now();
        // Emitter samples for direct light (a fixed stream: still scenes get still direct light).
        let lights = frame.emitter_samples(s.seed, self.renderer.config.light_samples as usize);
        lap(&mut stages, "light_samples", &mut t);
        // The first surfaces each VPL sees, evenly over its ISM tile (closes the tiles of VPLs
        // next to a surface, which the point set leaves full of holes).
        // The VPLs the GPU gathers: all but those the compensation alone reads (vpl::crevice).
        let gathered: std::borrow::Cow<[crate::vpl::ShadedVpl]> =
            if selection.shaded.iter().any(|v| v.near.is_some()) {
                let kept = selection.shaded.iter().filter(|v| v.near.is_none());
                kept.copied().collect::<Vec<_>>().into()
            } else {
                selection.shaded.as_slice().into()
            };
        let near =
            crate::gpu::ism::near_points(&self.tracer, &gathered, self.renderer.near_directions());
        lap(&mut stages, "ism_near", &mut t);
        // The light's temporal gradient, for accumulation under a moving light or object: only
        // when a vertex or an emitter sample moved (else the history is used whole, and the
        // last frame's probe paths are this frame's).
        let c = &self.renderer.config;
        let changed = moved || lights != self.last_lights || !self.gradient.primed();
        let gradient =
            if c.accumulate > 1 && c.history == crate::gpu::HistoryMode::Gradient && changed {
                self.gradient
                    .measure(&frame, &self.tracer, s.seed, (c.width, c.height), s.clamp)
            } else {
                None
            };
        self.last_lights.clone_from(&lights);
        lap(&mut stages, "gradient", &mut t);
        // 7. Emitter edges box-filtered by camera rays (CPU), for the sub-samples' steps: the
        // pixels an emitter's edge crosses and their box-filtered emission.
        let c = &self.renderer.config;
        let edges = crate::trace::edges::emitter_edges(
            &frame,
            &self.tracer,
            c.width,
            c.height,
            c.aa,
            c.edge_rays,
        );
        lap(&mut stages, "emitter_edges", &mut t);
        // 8. GPU: G-buffer, shadow maps, direct, ISMs, gather, compose, read back (with the
        // direct and indirect parts too where emitter edges need the emission they leave, and
        // a classical method's surface edges the light they replace).
        // With the clamping-bias compensation (instant radiosity only), the direct pass clamps
        // points on emitter triangles as the gather clamps VPLs, and the compensation adds
        // back what both leave out.
        let parts =
            components || !edges.is_empty() || (self.classical.is_some() && c.edge_rays > 0);
        let compensate = c.compensate > 0 && self.classical.is_none();
        let image = self.renderer.render(
            &GpuFrame {
                frame: &frame,
                vpls: &gathered,
                emitter_samples: &lights,
                clamp: s.clamp,
                direct_clamp: if compensate { s.clamp } else { 0.0 },
                near: &near,
                gradient: gradient.as_ref(),
            },
            parts,
        )?;
        stages.extend(image.timings.iter().map(|&(n, t)| (n, t)));
        let (image, solved, radiosity) = match &mut self.classical {
            Some(c) => {
                let (image, stats) = c.add_indirect(
                    image,
                    &frame,
                    &self.tracer,
                    &self.renderer,
                    parts,
                    &mut stages,
                )?;
                (image, Some(stats.is_some()), stats)
            }
            None => (image, None, None),
        };
        // Each emitter edge pixel's emission (the frame less its direct and indirect parts, as
        // the GPU's sub-samples saw it) replaced by its box filter.
        let mut image = image;
        t = Instant::now();
        let c = &self.renderer.config;
        if let (false, Some(d), Some(ind)) = (edges.is_empty(), &image.direct, &image.indirect) {
            for &(i, e) in &edges {
                let o = &mut image.hdr.data[i];
                let seen = *o - d.data[i] - ind.data[i];
                *o = (*o - seen + e).max(glam::Vec3::ZERO);
            }
            image.ldr = image.hdr.to_srgb8(c.exposure);
        }
        // A classical method's silhouettes and creases, box-filtered by camera rays through
        // its solution (CPU), in place of the sub-samples' steps: each ray sees the solution's
        // indirect light and the direct light of the frame's emitter samples, traced (what the
        // GPU's passes show inside surfaces, with exact visibility for the shadow maps').
        if let (Some(edge), Some(_), Some(_)) = (
            self.classical.as_ref().and_then(|c| c.edges.as_ref()),
            &image.direct,
            &image.indirect,
        ) {
            let cam = frame.camera;
            let (w, h) = (c.width, c.height);
            let els = &edge.reflected.elements;
            let hit = |p: glam::Vec2| {
                let d = cam.ray_dir(p, w, h);
                let hit = edge
                    .reflected
                    .tracer
                    .intersect(cam.position, d, f32::INFINITY)?;
                Some((d, hit.tri as usize, hit.b1, hit.b2))
            };
            let environment = frame.emitters.environment.as_deref();
            let edges = crate::trace::edges::surface_edges(
                (w, h),
                c.aa.min(2),
                c.edge_rays,
                frame.camera.position.length().max(1.0),
                |p| match hit(p) {
                    Some((_, e, b1, b2)) => {
                        let n = els.normals[e];
                        crate::trace::edges::Seen {
                            radiance: edge.reflected.at(e, b1, b2),
                            plane: Some((n, n.dot(els.tris[e][0]))),
                        }
                    }
                    None => crate::trace::edges::Seen {
                        radiance: glam::Vec3::ZERO,
                        plane: None,
                    },
                },
                |points| {
                    shade_edge(
                        points,
                        &hit,
                        edge,
                        &self.tracer,
                        &lights,
                        environment,
                        cam,
                        (w, h),
                    )
                },
            );
            if let (Some(dir), Some(ind)) = (&mut image.direct, &mut image.indirect) {
                for &(i, [l, li]) in &edges {
                    let o = &mut image.hdr.data[i];
                    *o = (*o - dir.data[i] - ind.data[i] + l).max(glam::Vec3::ZERO);
                    dir.data[i] = (l - li).max(glam::Vec3::ZERO);
                    ind.data[i] = li;
                }
            }
            if !edges.is_empty() {
                image.ldr = image.hdr.to_srgb8(c.exposure);
            }
            lap(&mut stages, "surface_edges", &mut t);
        }
        // Clamping-bias compensation (CPU): pixel surfaces, emitter samples, VPLs, clamp ->
        // the light the clamp left out near creases, added to the pixels (and the indirect).
        if compensate {
            let light = crate::compensation::Light {
                samples: &lights,
                vpls: &selection.shaded,
                clamp: s.clamp,
            };
            let added = crate::compensation::compensate(
                &frame,
                &self.tracer,
                (c.width, c.height),
                &light,
                (c.compensate, &image.hdr.data),
                s.seed,
            );
            for &(i, l) in &added {
                image.hdr.data[i] += l;
                if let Some(ind) = &mut image.indirect {
                    ind.data[i] += l;
                }
            }
            image.ldr = image.hdr.to_srgb8(c.exposure);
            lap(&mut stages, "compensation", &mut t);
        }
        if !components {
            (image.direct, image.indirect) = (None, None);
        }
        Ok(FrameOutput {
            index: f,
            time: frame.time,
            image,
            selection,
            stages,
            seconds: start.elapsed().as_secs_f64(),
            solved,
            radiosity,
        })
    }
}

/// A classical radiosity method in the frame: the solution, kept while the geometry and the
/// emitters are still, gives the indirect light; the GPU's passes give emission and direct
/// light as for instant radiosity (with no VPLs).
struct Classical {
    settings: radiosity::RadiositySettings,
    cache: radiosity::Cache,
    progress: Box<dyn Fn(&radiosity::SolveProgress) + Send + Sync>,
    pass: RadiosityPass,
    /// The solution as the CPU shows it, for the edges' camera rays (with `edge_rays`).
    edges: Option<EdgeShading>,
}

/// A solution's reflected light on its elements (with their BVH) and, per element corner, the
/// indirect part of it.
struct EdgeShading {
    reflected: radiosity::display::Shaded,
    indirect: Vec<[glam::Vec3; 3]>,
}

/// The mean over `points` (image points of one pixel, [`crate::trace::edges::fibonacci_lattice`])
/// of the light a classical method's frame shows there besides emission, and its indirect
/// part: the solution's indirect light (Gouraud) plus the direct light of the emitter samples
/// `lights`, traced; the environment where a ray meets nothing. `hit` casts a camera ray onto
/// the elements. The direct light is shaded once for each surface in each of the pixel's
/// 16 x 16 cells (at the first point there; the others on that surface in that cell take its
/// irradiance), so the points decide what the pixel covers, and more of them cost camera rays
/// more than shadow rays. Each emitter sample's visibility is traced at the first point of
/// each of the pixel's 4 x 4 cells and, where those disagree or a point lies on a surface none
/// of them met, at every shaded point: a shadow's edge crossing the pixel is traced in full,
/// its inside or outside costs 16 rays.
#[allow(clippy::too_many_arguments)]
fn shade_edge(
    points: &[glam::Vec2],
    hit: &(dyn Fn(glam::Vec2) -> Option<(glam::Vec3, usize, f32, f32)> + Sync),
    edge: &EdgeShading,
    tracer: &Tracer,
    lights: &[crate::scene::EmitterSample],
    environment: Option<&crate::scene::Environment>,
    cam: crate::scene::camera::Camera,
    (w, h): (u32, u32),
) -> [glam::Vec3; 2] {
    use crate::trace::edges::same_plane;
    use glam::Vec3;
    let els = &edge.reflected.elements;
    struct At {
        x: Vec3,
        n: Vec3,
        albedo: Vec3,
        plane: (Vec3, f32),
    }
    // Each point's cell in a `cells x cells` grid over its pixel.
    let cell = |p: glam::Vec2, cells: u32| {
        let f = (p - p.floor()) * cells as f32;
        let c = |v: f32| (v.max(0.0) as u32).min(cells - 1);
        c(f.y) * cells + c(f.x)
    };
    let scale = cam.position.length().max(1.0);
    // Per point: the surface it sees, and what it shows besides the direct light (the
    // environment, or the solution's indirect light) with that indirect part.
    let mut own = Vec::with_capacity(points.len());
    let mut at = Vec::with_capacity(points.len());
    for &p in points {
        let Some((d, e, b1, b2)) = hit(p) else {
            // The environment toward the pixel's centre, as the direct pass gives it.
            let centre = p.floor() + glam::Vec2::splat(0.5);
            let sky = environment.map_or(Vec3::ZERO, |env| env.radiance(cam.ray_dir(centre, w, h)));
            own.push([sky, Vec3::ZERO]);
            at.push(None);
            continue;
        };
        let n = els.normals[e];
        let n = if n.dot(d) > 0.0 { -n } else { n };
        let indirect = radiosity::form_factor::at(&edge.indirect[e], [1.0 - b1 - b2, b1, b2]);
        own.push([indirect, indirect]);
        let x = els.point(e, b1, b2);
        at.push(Some(At {
            x,
            n,
            albedo: els.albedo(e),
            plane: (n, n.dot(x)),
        }));
    }
    // The point whose irradiance each point takes: the first on its surface in its cell.
    // Per cell: (the surface's plane, its first point).
    type First = ((Vec3, f32), usize);
    let mut firsts: Vec<Vec<First>> = vec![Vec::new(); 256];
    let source: Vec<usize> = (0..at.len())
        .map(|k| {
            let Some(a) = &at[k] else { return k };
            let list = &mut firsts[cell(points[k], 16) as usize];
            match list.iter().find(|f| same_plane(f.0, a.plane, scale)) {
                Some(f) => f.1,
                None => {
                    list.push((a.plane, k));
                    k
                }
            }
        })
        .collect();
    // The probes: the first point of each 4 x 4 cell.
    let mut probe = vec![false; at.len()];
    let mut taken = [false; 16];
    for (k, &p) in points.iter().enumerate() {
        let c = cell(p, 4) as usize;
        if !taken[c] {
            (taken[c], probe[k]) = (true, true);
        }
    }
    let probed: Vec<(Vec3, f32)> = (0..at.len())
        .filter(|&k| probe[k])
        .filter_map(|k| at[k].as_ref().map(|a| a.plane))
        .collect();
    let on_probed: Vec<bool> = at
        .iter()
        .map(|a| {
            a.as_ref()
                .is_some_and(|a| probed.iter().any(|&p| same_plane(p, a.plane, scale)))
        })
        .collect();
    let mut irradiance = vec![Vec3::ZERO; at.len()];
    // Per point, this sample's visibility where a probe traced it.
    let mut seen: Vec<Option<bool>> = vec![None; at.len()];
    for l in lights {
        // The probes' visibility of this sample: Some(v) if all that it lights agree.
        let mut shared: Option<Option<bool>> = None;
        for (k, a) in at.iter().enumerate() {
            seen[k] = None;
            let Some(a) = a else { continue };
            if !probe[k] {
                continue;
            }
            if let Some((_, y, ny)) = l.irradiance_at(a.x, a.n) {
                let v = !tracer.occluded(a.x, a.n, y, ny);
                seen[k] = Some(v);
                shared = match shared {
                    None => Some(Some(v)),
                    Some(Some(s)) if s == v => Some(Some(v)),
                    _ => Some(None),
                };
            }
        }
        for (k, (a, &on_probed)) in at.iter().zip(&on_probed).enumerate() {
            let Some(a) = a else { continue };
            if source[k] != k {
                continue;
            }
            if let Some((e, y, ny)) = l.irradiance_at(a.x, a.n) {
                let visible = match (seen[k], shared) {
                    (Some(v), _) => v,
                    (None, Some(Some(v))) if on_probed => v,
                    _ => !tracer.occluded(a.x, a.n, y, ny),
                };
                if visible {
                    irradiance[k] += e;
                }
            }
        }
    }
    let mut sum = [Vec3::ZERO; 2];
    for (k, a) in at.iter().enumerate() {
        let direct = a.as_ref().map_or(Vec3::ZERO, |a| {
            a.albedo * irradiance[source[k]] / std::f32::consts::PI
        });
        sum[0] += own[k][0] + direct;
        sum[1] += own[k][1];
    }
    sum.map(|v| v / points.len().max(1) as f32)
}

impl Classical {
    /// Solves if the scene changed, rasterizes the solution's indirect part (Gouraud) on the
    /// GPU and adds it to the frame's emission and direct light.
    fn add_indirect(
        &mut self,
        mut image: RenderedImage,
        frame: &crate::scene::Frame,
        tracer: &Tracer,
        renderer: &Renderer,
        components: bool,
        stages: &mut Vec<(&'static str, f64)>,
    ) -> Result<(RenderedImage, Option<radiosity::Stats>)> {
        let mut t = Instant::now();
        let (solution, solved) = self
            .cache
            .get(frame, tracer, &self.settings, &*self.progress);
        if solved {
            let shaded =
                radiosity::display::Shaded::new(frame, solution, radiosity::Part::Indirect);
            // Emission comes from the compose pass, as for instant radiosity.
            self.pass.upload_with(&renderer.gpu, &shaded, false);
            self.edges = (renderer.config.edge_rays > 0).then(|| EdgeShading {
                reflected: radiosity::display::Shaded::new(
                    frame,
                    solution,
                    radiosity::Part::Reflected,
                ),
                indirect: shaded.corners,
            });
        }
        lap(stages, "radiosity_solve", &mut t);
        let indirect = self.pass.render(&renderer.gpu, frame)?;
        for (o, i) in image.hdr.data.iter_mut().zip(&indirect.data) {
            *o += *i;
        }
        image.ldr = image.hdr.to_srgb8(renderer.config.exposure);
        if components {
            image.indirect = Some(indirect);
        }
        lap(stages, "radiosity_display", &mut t);
        Ok((image, solved.then(|| solution.stats.clone())))
    }
}
