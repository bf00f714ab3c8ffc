//! The view's state and its update step, without a window: the settings (scene, method,
//! sampler and knobs, VPL count, quality, size), the camera, the time, and one renderer state
//! per half of the view (one, or two in the split view, each a sampler or a method). [`App::apply`]
//! takes an [`Input`]; [`App::step`] renders the next frame of each half with the same
//! [`Pipeline`] as `irad render`, and measures the frame rate, the passes' times and each
//! half's live flicker (frame to frame, and against a cached reference where there is one);
//! [`App::shown`] is what a half shows (its image, a component, the heat map, the overlays).

use super::camera;
use super::overlay::{self, Overlay, Overlays};
use super::reference::{AgainstReference, References};
use crate::config::{self, CameraSpec, Method, Size};
use crate::frame::{FrameOutput, Pipeline, SamplerKind};
use crate::gpu::Gpu;
use crate::image::Hdr;
use crate::math::luminance;
use crate::scene::Scene;
use anyhow::{anyhow, bail, Result};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// One change asked of the view (by the panel, the mouse and keys, or a test).
#[derive(Clone, Debug, PartialEq)]
pub enum Input {
    /// Turn the eye about the target (degrees: yaw right, pitch up).
    Orbit {
        yaw: f32,
        pitch: f32,
    },
    /// Slide the camera across the view (fractions of the view's height: right, up).
    Pan {
        dx: f32,
        dy: f32,
    },
    /// Move toward the target (steps of a tenth of the distance; negative: away).
    Dolly(f32),
    /// Fly along the view's axes, in seconds of travel (the speed is a fifth of the scene's
    /// size a second): forward, right, up.
    Fly {
        forward: f32,
        right: f32,
        up: f32,
    },
    /// Back to the scene's own camera (animated if it is).
    ResetCamera,
    Play(bool),
    /// Set the time (seconds; kept within the animation).
    Scrub(f32),
    Scene(String),
    /// The left half's method.
    Method(Method),
    /// The left half's sampler.
    Sampler(SamplerKind),
    /// The split view's right half (None: one view).
    Split(Option<Variant>),
    Vpls(u32),
    /// A sampler knob by name (see `config::KNOBS`).
    Knob(&'static str, f64),
    Aa(u32),
    IsmSize(u32),
    Exposure(f32),
    /// A fixed render size (None: picked from the frame time, see [`AutoSize`]).
    Size(Option<Size>),
    /// Show each half's flicker as a heat map in place of its image.
    Heat(bool),
    /// Show the whole frame, or its direct or indirect light only.
    Component(Component),
    /// Turn an overlay on or off.
    Overlay(Overlay, bool),
    /// Print the current view as `--camera EYE:TARGET:FOV` and the `irad render` command line
    /// (stdout, and the panel's message), and put both on the clipboard (the window does).
    CopyView,
    /// Save each half's last frame (EXR and PNG) in the output folder.
    SaveFrame,
}

/// The methods the view offers (`--method`'s).
pub const METHODS: [Method; 4] = [
    Method::Instant,
    Method::Progressive,
    Method::Hierarchical,
    Method::Stochastic,
];

/// What a half renders with: a method and, for instant radiosity, its sampler.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Variant {
    pub method: Method,
    pub sampler: SamplerKind,
}

impl From<SamplerKind> for Variant {
    /// Instant radiosity with sampler `s`.
    fn from(s: SamplerKind) -> Variant {
        Variant {
            method: Method::Instant,
            sampler: s,
        }
    }
}

impl Variant {
    /// The sampler's name for instant radiosity, else the method's.
    pub fn name(self) -> &'static str {
        if self.method == Method::Instant {
            self.sampler.name()
        } else {
            self.method.name()
        }
    }

    /// A `--split` word: a sampler (instant radiosity with it) or a method (with `base`'s
    /// sampler, which only instant radiosity reads).
    pub fn parse(word: &str, base: &config::Render) -> Result<Variant> {
        let w = word.trim();
        if let Some(s) = SamplerKind::parse(w) {
            return Ok(s.into());
        }
        if let Some(&m) = METHODS.iter().find(|m| m.name() == w) {
            return Ok(Variant {
                method: m,
                sampler: base.sampler.kind,
            });
        }
        let samplers: Vec<&str> = SamplerKind::ALL.iter().map(|s| s.name()).collect();
        let methods: Vec<&str> = METHODS.iter().map(|m| m.name()).collect();
        bail!(
            "`split` {w:?} is neither a sampler ({}) nor a method ({})",
            samplers.join(", "),
            methods.join(", ")
        )
    }
}

/// What a half shows: the whole frame, or one of its components (`irad render --components`'
/// images: the direct light, and the indirect light; emission and the CPU's emitter edges are
/// in neither).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum Component {
    /// The whole frame
    #[default]
    #[cfg_attr(feature = "cli", value(name = "frame"))]
    Full,
    /// The direct light only
    Direct,
    /// The indirect light only
    Indirect,
}

/// How the render size follows the frame time when it is not fixed (docs/view.md): every
/// [`AutoSize::EVERY`] frames, the height is scaled by sqrt(target / mean seconds the halves'
/// rendering took; the window's drawing does not scale with the size and is left out) (the
/// cost is about proportional to the pixels), clamped to 0.5..2 per change, to a multiple of
/// 8 between [`AutoSize::MIN_HEIGHT`] and the room the window gives, and changed only when that
/// moves it by 15% or more. The target is 10 frames a second on a software adapter
/// (llvmpipe, lavapipe: device type Cpu) and 30 on a GPU; a software adapter starts at 128
/// pixels high, a GPU at the room the window gives.
#[derive(Clone, Debug, PartialEq)]
pub struct AutoSize {
    pub target_s: f64,
    pub max_height: u32,
    /// Frame times since the last change (the first frame after a change, which builds the
    /// renderer, is left out).
    times: Vec<f64>,
}

impl AutoSize {
    pub const EVERY: usize = 3;
    pub const MIN_HEIGHT: u32 = 64;
    pub const SOFTWARE_START: u32 = 128;

    /// The rule for an adapter: software (`cpu`) or not, with `max_height` of room.
    pub fn new(cpu: bool, max_height: u32) -> AutoSize {
        AutoSize {
            target_s: if cpu { 0.1 } else { 1.0 / 30.0 },
            max_height: max_height.max(Self::MIN_HEIGHT),
            times: Vec::new(),
        }
    }
    /// The height to start at.
    pub fn start(&self, cpu: bool) -> u32 {
        if cpu {
            Self::SOFTWARE_START.min(self.max_height)
        } else {
            self.max_height
        }
    }
    /// Records a frame's seconds at `height`; the new height when the rule changes it.
    pub fn record(&mut self, height: u32, seconds: f64, first_after_change: bool) -> Option<u32> {
        if first_after_change {
            return None;
        }
        self.times.push(seconds);
        if self.times.len() < Self::EVERY {
            return None;
        }
        let mean = self.times.iter().sum::<f64>() / self.times.len() as f64;
        self.times.clear();
        let scale = (self.target_s / mean.max(1e-6)).sqrt().clamp(0.5, 2.0);
        let want = (height as f64 * scale / 8.0).round() as u32 * 8;
        let want = want.clamp(Self::MIN_HEIGHT, self.max_height.max(Self::MIN_HEIGHT));
        let moved = (want as f64 - height as f64).abs() >= 0.15 * height as f64;
        (moved && want != height).then_some(want)
    }
}

/// The live flicker of a half: the frame-to-frame change of its indirect light while nothing
/// in the view moved (same camera, time and settings), F1 = mean over pixels of
/// |lum(I_t) - lum(I_t-1)| (`irad metrics`' F1 against a still reference), also relative to
/// the mean indirect luminance; and the mean of both over the still frames so far.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Flicker {
    /// This frame's F1 (None: something moved, or the first frame).
    pub f1: Option<f64>,
    pub relative: Option<f64>,
    /// Mean F1 and relative F1 over the still frames since the last change.
    pub mean_f1: f64,
    pub mean_relative: f64,
    pub still_frames: u32,
    /// Per pixel |lum(I_t) - lum(I_t-1)| of the last still frame.
    pub map: Option<Vec<f32>>,
}

/// F1 between two indirect images, its mean-relative value and the per-pixel change.
pub fn flicker_of(now: &Hdr, before: &Hdr) -> (f64, f64, Vec<f32>) {
    let map: Vec<f32> = now
        .data
        .iter()
        .zip(&before.data)
        .map(|(a, b)| (luminance(*a) - luminance(*b)).abs())
        .collect();
    let n = map.len().max(1) as f64;
    let f1 = map.iter().map(|&d| d as f64).sum::<f64>() / n;
    let mean = now.data.iter().map(|c| luminance(*c) as f64).sum::<f64>() / n;
    (f1, if mean > 0.0 { f1 / mean } else { 0.0 }, map)
}

/// A heat map of per-pixel change: black at 0, red, then yellow and white at `scale` and
/// above (sRGB bytes, RGB).
pub fn heat_map(map: &[f32], scale: f32) -> Vec<u8> {
    let mut out = Vec::with_capacity(map.len() * 3);
    for &d in map {
        let x = (d / scale.max(1e-12)).clamp(0.0, 1.0) * 3.0;
        let c = [
            x.min(1.0),
            (x - 1.0).clamp(0.0, 1.0),
            (x - 2.0).clamp(0.0, 1.0),
        ];
        out.extend(c.iter().map(|v| (v * 255.0).round() as u8));
    }
    out
}

/// One half of the view: a sampler's (or method's) own renderer state and its last frame.
pub struct Half {
    pub sampler: SamplerKind,
    pub variant: Variant,
    pipeline: Pipeline,
    /// The last frame rendered (None before the first).
    pub output: Option<FrameOutput>,
    pub flicker: Flicker,
    /// The last frame against the cached reference of its time (None: none cached).
    pub reference: Option<AgainstReference>,
    /// For each VPL slot of the last frame, whether it kept the VPL of the frame before (the
    /// same light path and bounce; the sampler's `replaced` is the fraction that did not).
    pub kept: Vec<bool>,
    /// What the last frame saw (camera, time), to tell whether anything moved since.
    seen: Option<(CameraSpec, f32)>,
}

/// What the view starts with.
#[derive(Clone, Debug)]
pub struct Start {
    /// The render settings (`irad render`'s flags): scene, method, sampler, VPLs, quality.
    pub render: config::Render,
    /// The split view's right half.
    pub split: Option<Variant>,
    /// Render at `render.sequence.size` always (else the size follows the frame time).
    pub fixed_size: bool,
    /// Still frames before each step up in size (0: never; see [`App::refine_after`]).
    pub refine_after: u32,
    /// `irad compare`'s cache of references (None: no look-up).
    pub cache: Option<PathBuf>,
    /// What the halves show, and the overlays on at the start.
    pub component: Component,
    pub overlays: Overlays,
}

/// The view: settings, camera, time, and its halves' renderer states.
pub struct App {
    pub gpu: Arc<Gpu>,
    /// The settings the halves render with (the left half's method and sampler in `method`
    /// and `sampler.kind`).
    pub cfg: config::Render,
    pub split: Option<Variant>,
    /// The scene as loaded (its own camera).
    scene: Scene,
    /// The camera the user moved to (None: the scene's own, animated if it is).
    pub camera: Option<CameraSpec>,
    pub time: f32,
    pub playing: bool,
    /// Frames drawn since start: the sampler's frame index (its random streams and history
    /// follow it, also while time stands still).
    pub index: u32,
    pub halves: Vec<Half>,
    /// The halves must be rebuilt before the next frame (settings changed).
    rebuild: bool,
    /// The frame after a rebuild (its time includes building the renderer).
    first_after_build: bool,
    pub auto: Option<AutoSize>,
    /// Refining while still: after this many frames in a row that saw the same camera, time
    /// and settings, the height steps up by half (a multiple of 8) up to the size rule's
    /// room, again after as many frames at each size; the first change goes back to the size
    /// the rule picked. Only with the size rule on; 0: never.
    pub refine_after: u32,
    /// While refined: the size the rule picked (None: not refined).
    pub interactive: Option<Size>,
    /// Frames in a row that saw the same camera, time and settings.
    pub still_steps: u32,
    /// Something moved or a setting changed since the last step.
    moved: bool,
    /// The camera and time of the last step.
    last_seen: Option<(CameraSpec, f32)>,
    pub heat: bool,
    pub component: Component,
    pub overlays: Overlays,
    /// `irad compare`'s cached references.
    pub references: Option<References>,
    /// What the window is to put on the clipboard (taken by it).
    pub clipboard: Option<String>,
    /// Build new halves (a setting changed) on another thread, and a classical method's first
    /// solve with them, while the old halves go on drawing; swapped in at the first step after
    /// they are ready. Off: built in the step (what the tests drive); the window turns it on.
    pub background: bool,
    /// The halves being built on another thread.
    building: Option<std::sync::mpsc::Receiver<Result<Vec<Half>>>>,
    /// Seconds from one step to the next, the median of the last 15 (frame rate = 1 / this).
    pub frame_seconds: f64,
    /// Seconds the halves' rendering took, the median of the last 15 steps that did not
    /// rebuild them (the rest of a frame is the window's: the controls, the copy to the
    /// screen).
    pub render_seconds: f64,
    intervals: Vec<f64>,
    render_times: Vec<f64>,
    /// The halves' stages (summed over the halves) of the steps `render_times` holds.
    stage_times: Vec<Vec<(&'static str, f64)>>,
    last_step: Option<Instant>,
    /// What the view last said (a command line, a saved file, an error).
    pub message: String,
    /// The files the last `SaveFrame` wrote.
    pub saved: Vec<PathBuf>,
}

impl App {
    /// Loads the scene and builds the halves (checks the settings as `irad render` does).
    pub fn new(gpu: Arc<Gpu>, start: &Start) -> Result<App> {
        let mut cfg = start.render.clone();
        cfg.validate()?;
        // The view moves the camera itself: `--camera` is where it starts.
        let camera = cfg.sequence.camera.take();
        let scene = cfg.sequence.load_scene(config::DEFAULT_STILL_SCENE)?;
        let cpu = is_software(&gpu);
        let auto = (!start.fixed_size).then(|| {
            let a = AutoSize::new(cpu, cfg.sequence.size.height);
            cfg.sequence.size = sized(cfg.sequence.size, a.start(cpu));
            a
        });
        let mut app = App {
            gpu,
            cfg,
            split: start.split,
            scene,
            camera,
            time: 0.0,
            playing: false,
            index: 0,
            halves: Vec::new(),
            rebuild: true,
            first_after_build: true,
            auto,
            refine_after: start.refine_after,
            interactive: None,
            still_steps: 0,
            moved: true,
            last_seen: None,
            heat: false,
            component: start.component,
            overlays: start.overlays,
            references: start.cache.clone().map(References::new),
            clipboard: None,
            background: false,
            building: None,
            frame_seconds: 0.0,
            render_seconds: 0.0,
            intervals: Vec::new(),
            render_times: Vec::new(),
            stage_times: Vec::new(),
            last_step: None,
            message: String::new(),
            saved: Vec::new(),
        };
        app.build()?;
        Ok(app)
    }

    /// The scene's length in seconds (0: still).
    pub fn duration(&self) -> f32 {
        self.scene.duration()
    }

    /// The samplers of the halves, left first.
    pub fn samplers(&self) -> Vec<SamplerKind> {
        self.variants().iter().map(|v| v.sampler).collect()
    }

    /// What the halves render with, left first.
    pub fn variants(&self) -> Vec<Variant> {
        let mut v = vec![Variant {
            method: self.cfg.method,
            sampler: self.cfg.sampler.kind,
        }];
        v.extend(self.split);
        v
    }

    /// The camera in use: the user's, or the scene's at the current time.
    pub fn current_camera(&self) -> CameraSpec {
        self.camera
            .unwrap_or_else(|| camera::of_scene(&self.scene, self.time))
    }

    /// What building the halves takes, for [`build_halves`] on this thread or another.
    fn build_job(&self) -> BuildJob {
        BuildJob {
            gpu: self.gpu.clone(),
            cfg: self.cfg.clone(),
            variants: self.variants(),
            scene: self.scene.clone(),
            camera: self.camera,
            at: (self.index, self.time),
        }
    }

    fn build(&mut self) -> Result<()> {
        let mut job = self.build_job();
        // On this thread a classical method solves in its first frame, as before.
        job.at.1 = f32::NAN;
        self.halves = build_halves(job)?;
        self.rebuild = false;
        self.first_after_build = true;
        Ok(())
    }

    /// Whether new halves are being built on another thread (see [`App::background`]).
    pub fn building(&self) -> bool {
        self.building.is_some()
    }

    /// Applies one input. A change the settings refuse (a bad knob value, a scene that does
    /// not load) leaves the view as it was and returns the error.
    pub fn apply(&mut self, input: Input) -> Result<()> {
        let cam = |app: &mut App, f: &dyn Fn(&mut CameraSpec)| {
            let mut c = app.current_camera();
            f(&mut c);
            app.camera = Some(c);
        };
        let mut cfg = self.cfg.clone();
        // What only changes what is shown (or writes it out) moves nothing.
        let shows = matches!(
            input,
            Input::Heat(_)
                | Input::Component(_)
                | Input::Overlay(..)
                | Input::CopyView
                | Input::SaveFrame
                | Input::Play(false)
        );
        match input {
            Input::Orbit { yaw, pitch } => cam(self, &|c| camera::orbit(c, yaw, pitch)),
            Input::Pan { dx, dy } => cam(self, &|c| camera::pan(c, dx, dy)),
            Input::Dolly(s) => cam(self, &|c| camera::dolly(c, s)),
            Input::Fly { forward, right, up } => {
                let (lo, hi) = self.scene.at(self.time).bounds();
                let speed = 0.2 * (hi - lo).length().max(1e-3);
                cam(self, &|c| {
                    camera::fly(c, forward * speed, right * speed, up * speed)
                })
            }
            Input::ResetCamera => {
                self.camera = None;
                self.rebuild = true;
            }
            Input::Play(p) => self.playing = p,
            Input::Scrub(t) => self.time = t.clamp(0.0, self.duration()),
            Input::Scene(spec) => {
                cfg.sequence.scene = Some(spec);
                let scene = cfg.sequence.load_scene(config::DEFAULT_STILL_SCENE)?;
                self.scene = scene;
                self.camera = None;
                self.time = 0.0;
                self.rebuild = true;
            }
            Input::Method(m) => cfg.method = m,
            Input::Sampler(s) => cfg.sampler.kind = s,
            Input::Split(s) => {
                self.split = s;
                self.rebuild = true;
            }
            Input::Vpls(v) => cfg.vpls = v,
            Input::Knob(name, v) => {
                let k = config::Knob::named(name).ok_or_else(|| anyhow!("no knob `{name}`"))?;
                k.check(v)?;
                k.set(&mut cfg.sampler.knobs, v);
            }
            Input::Aa(a) => cfg.quality.aa = a,
            Input::IsmSize(s) => cfg.quality.ism_size = s,
            Input::Exposure(e) => cfg.exposure = e,
            Input::Size(s) => match s {
                Some(s) => {
                    cfg.sequence.size = s;
                    self.auto = None;
                    self.interactive = None;
                }
                None => {
                    let cpu = is_software(&self.gpu);
                    let a = AutoSize::new(cpu, cfg.sequence.size.height.max(256));
                    cfg.sequence.size = sized(cfg.sequence.size, a.start(cpu));
                    self.auto = Some(a);
                    self.interactive = None;
                }
            },
            Input::Heat(h) => self.heat = h,
            Input::Component(c) => self.component = c,
            Input::Overlay(o, on) => self.overlays.set(o, on),
            Input::CopyView | Input::SaveFrame if self.building.is_some() => {
                bail!("the view is being rebuilt for the new settings: copy or save once it shows them")
            }
            Input::CopyView => {
                let cam = camera::rounded(&self.shown_camera());
                self.message = format!("--camera {cam}\n{}", self.command_line());
                self.clipboard = Some(self.message.clone());
                crate::outln!("{}", self.message)?;
            }
            Input::SaveFrame => {
                self.saved = self.save_frame()?;
                let names: Vec<String> =
                    self.saved.iter().map(|p| p.display().to_string()).collect();
                self.message = format!("wrote {}", names.join(", "));
                crate::outln!("{}", self.message)?;
            }
        }
        if !same_settings(&cfg, &self.cfg) {
            cfg.validate()?;
            self.cfg = cfg;
            self.rebuild = true;
        }
        if !shows {
            self.moved = true;
        }
        Ok(())
    }

    /// Renders at height `h` from the next frame on (the width keeps the aspect).
    pub fn set_height(&mut self, h: u32) {
        let size = sized(self.cfg.sequence.size, h);
        if size != self.cfg.sequence.size {
            self.cfg.sequence.size = size;
            self.rebuild = true;
        }
    }

    /// Renders the next frame of each half (rebuilding them first when the settings
    /// changed), advances the time when playing, and measures.
    pub fn step(&mut self) -> Result<()> {
        // Moved (or a setting changed): back to the size the rule picked.
        let seen = (self.current_camera(), self.time);
        let moved = std::mem::replace(&mut self.moved, false)
            || self.playing
            || self.last_seen != Some(seen);
        self.last_seen = Some(seen);
        if moved {
            self.still_steps = 0;
            if let Some(s) = self.interactive.take() {
                if s != self.cfg.sequence.size {
                    self.cfg.sequence.size = s;
                    self.rebuild = true;
                }
            }
        }
        // New halves built on another thread: swap them in when ready.
        if let Some(rx) = &self.building {
            match rx.try_recv() {
                Ok(halves) => {
                    self.building = None;
                    self.halves = halves?;
                    self.first_after_build = true;
                }
                Err(std::sync::mpsc::TryRecvError::Empty) => {}
                Err(std::sync::mpsc::TryRecvError::Disconnected) => {
                    self.building = None;
                    bail!("building the renderers failed (their thread ended)");
                }
            }
        }
        if self.rebuild {
            if !self.background || self.halves.is_empty() {
                self.build()?;
            } else if self.building.is_none() {
                // (While one is being built, a further change waits for it.)
                let job = self.build_job();
                let (tx, rx) = std::sync::mpsc::channel();
                std::thread::Builder::new()
                    .name("irad view build".into())
                    .spawn(move || {
                        let _ = tx.send(build_halves(job));
                    })
                    .map_err(|e| anyhow!("cannot start a thread to build the renderers: {e}"))?;
                self.building = Some(rx);
                self.rebuild = false;
            }
        }
        let now = Instant::now();
        if let Some(last) = self.last_step {
            // The median of the last intervals: a frame that rebuilt the halves is not the
            // rate.
            self.intervals.push(now.duration_since(last).as_secs_f64());
            if self.intervals.len() > 15 {
                self.intervals.remove(0);
            }
            self.frame_seconds = median(&self.intervals);
        }
        self.last_step = Some(now);
        let view = self.camera;
        let reference = self.reference_frame();
        let started = Instant::now();
        for h in &mut self.halves {
            if let Some(c) = &view {
                if h.seen.is_none_or(|(s, _)| s != *c) {
                    c.apply(&mut h.pipeline.scene)?;
                }
            }
            let out = h.pipeline.render_at(self.index, self.time, true)?;
            let still = h.seen == Some(seen);
            let before = h.output.as_ref().and_then(|o| o.image.indirect.as_ref());
            match (out.image.indirect.as_ref(), before, still) {
                (Some(now), Some(before), true) => {
                    let (f1, rel, map) = flicker_of(now, before);
                    let fl = &mut h.flicker;
                    let n = fl.still_frames as f64;
                    fl.mean_f1 = (fl.mean_f1 * n + f1) / (n + 1.0);
                    fl.mean_relative = (fl.mean_relative * n + rel) / (n + 1.0);
                    fl.still_frames += 1;
                    fl.f1 = Some(f1);
                    fl.relative = Some(rel);
                    fl.map = Some(map);
                }
                _ => h.flicker = Flicker::default(),
            }
            // Which slots kept their VPL (the sampler's `replaced`, slot by slot).
            let key = |v: &crate::vpl::paths::Vpl| (v.path, v.depth);
            let keys: Vec<_> = out.selection.vpls.iter().map(key).collect();
            let before: Vec<_> = h
                .output
                .as_ref()
                .map(|o| o.selection.vpls.iter().map(key).collect())
                .unwrap_or_default();
            h.kept = if before.len() == keys.len() {
                keys.iter().zip(&before).map(|(a, b)| a == b).collect()
            } else {
                vec![false; keys.len()]
            };
            h.reference = match &reference {
                Some((spp, f, r)) => {
                    let img = &out.image.hdr;
                    let relmse = crate::metrics::frame_error(img, r)?.rel_mse;
                    let error = crate::metrics::error_image(img, r);
                    let last = h.reference.take();
                    // The frame before's error: the same frame (nothing moved) or the one
                    // before it (playing).
                    let f1 = last
                        .as_ref()
                        .filter(|l| {
                            l.error.len() == error.len() && (l.frame == *f || l.frame + 1 == *f)
                        })
                        .map(|l| {
                            let n = error.len().max(1) as f64;
                            error
                                .iter()
                                .zip(&l.error)
                                .map(|(a, b)| (a - b).abs())
                                .sum::<f64>()
                                / n
                        });
                    let (mut mean_f1, mut frames) = last
                        .filter(|_| f1.is_some())
                        .map_or((0.0, 0), |l| (l.mean_f1, l.frames));
                    if let Some(v) = f1 {
                        mean_f1 = (mean_f1 * frames as f64 + v) / (frames as f64 + 1.0);
                        frames += 1;
                    }
                    Some(AgainstReference {
                        spp: *spp,
                        frame: *f,
                        relmse,
                        f1,
                        mean_f1,
                        frames,
                        error,
                    })
                }
                None => None,
            };
            h.seen = Some(seen);
            h.output = Some(out);
        }
        let seconds = started.elapsed().as_secs_f64();
        let first = std::mem::replace(&mut self.first_after_build, false);
        if !first {
            self.render_times.push(seconds);
            if self.render_times.len() > 15 {
                self.render_times.remove(0);
            }
            self.render_seconds = median(&self.render_times);
            // Each stage of the halves' frames (summed over the halves), over the same steps.
            let mut stages: Vec<(&'static str, f64)> = Vec::new();
            for o in self.halves.iter().filter_map(|h| h.output.as_ref()) {
                for &(name, t) in &o.stages {
                    match stages.iter_mut().find(|(n, _)| *n == name) {
                        Some(s) => s.1 += t,
                        None => stages.push((name, t)),
                    }
                }
            }
            self.stage_times.push(stages);
            if self.stage_times.len() > 15 {
                self.stage_times.remove(0);
            }
        } else {
            self.stage_times.clear();
        }
        let height = self.cfg.sequence.size.height;
        if !moved {
            self.still_steps += 1;
        }
        let room = self.auto.as_ref().map(|a| a.max_height);
        match room {
            // Still long enough, and room to grow: one step up.
            Some(room)
                if self.refine_after > 0
                    && self.still_steps >= self.refine_after
                    && height < room =>
            {
                let up = ((height as f64 * 1.5 / 8.0).round() as u32 * 8).min(room);
                self.interactive.get_or_insert(self.cfg.sequence.size);
                self.set_height(up);
                self.still_steps = 0;
            }
            // Refined, or new halves being built: the rule waits.
            Some(_) if self.interactive.is_some() || self.building.is_some() => {}
            _ => {
                if let Some(h) = self
                    .auto
                    .as_mut()
                    .and_then(|a| a.record(height, seconds, first))
                {
                    self.set_height(h);
                }
            }
        }
        self.index += 1;
        if self.playing {
            let d = self.duration();
            self.time += 1.0 / self.cfg.sequence.fps;
            if self.time > d {
                self.time = 0.0;
            }
        }
        Ok(())
    }

    /// How many steps [`App::stage_medians`] are the median of.
    pub fn render_samples(&self) -> usize {
        self.stage_times.len()
    }

    /// Each stage's median seconds over the last 15 steps that did not rebuild the halves
    /// (CPU stages and GPU passes, summed over the halves), in the frames' order; with
    /// `render_seconds` what `--screenshot` prints and benches/view_fps.py reads.
    pub fn stage_medians(&self) -> Vec<(&'static str, f64)> {
        let Some(last) = self.stage_times.last() else {
            return Vec::new();
        };
        last.iter()
            .map(|&(name, _)| {
                let v: Vec<f64> = self
                    .stage_times
                    .iter()
                    .map(|s| s.iter().find(|(n, _)| *n == name).map_or(0.0, |x| x.1))
                    .collect();
                (name, median(&v))
            })
            .collect()
    }

    /// The reference of the frame about to be rendered, if `irad compare` cached one for it:
    /// (spp, frame number, image). Only at a frame's time (time x fps a whole number).
    fn reference_frame(&mut self) -> Option<(u32, u32, Hdr)> {
        let fps = self.cfg.sequence.fps as f64;
        let f = (self.time as f64 * fps).round();
        if (f / fps - self.time as f64).abs() > 1e-4 || f < 0.0 {
            return None;
        }
        let refs = self.references.as_mut()?;
        let (folder, spp) = refs.folder(&self.cfg, self.camera)?;
        let img = refs.frame(&folder, spp, f as u32, self.cfg.sequence.size)?;
        Some((spp, f as u32, img))
    }

    /// The sRGB bytes (RGB) half `i` shows: its last frame (or its direct or indirect light,
    /// see [`Component`]), or its flicker heat map (with the heat map on; black before the
    /// first still frame); then the overlays turned on.
    pub fn shown(&self, i: usize) -> Option<(u32, u32, Vec<u8>)> {
        let h = self.halves.get(i)?;
        let o = h.output.as_ref()?;
        let (w, ht) = (o.image.hdr.width, o.image.hdr.height);
        let mut bytes = if self.heat {
            // Full scale at 4 times the mean indirect luminance's 10%.
            let ind = o.image.indirect.as_ref()?;
            let mean = ind.mean();
            let scale = 0.4 * luminance(mean).max(1e-6);
            match &h.flicker.map {
                Some(m) => heat_map(m, scale),
                None => vec![0; (w * ht * 3) as usize],
            }
        } else {
            match self.component {
                Component::Full => o.image.ldr.clone(),
                Component::Direct => o.image.direct.as_ref()?.to_srgb8(self.cfg.exposure),
                Component::Indirect => o.image.indirect.as_ref()?.to_srgb8(self.cfg.exposure),
            }
        };
        let ov = self.overlays;
        if ov.vpls || ov.shadow_faces {
            let frame = h.pipeline.scene.at(o.time);
            if ov.shadow_faces {
                let r = &h.pipeline.renderer.config;
                let samples =
                    frame.emitter_samples(h.pipeline.params.seed, r.light_samples as usize);
                let (lo, hi) = frame.bounds();
                let length = 0.08 * (hi - lo).length();
                let faces = overlay::shadow_faces(&frame, &samples, r.shadow_size, length);
                overlay::draw_faces(&mut bytes, w, ht, &frame.camera, &faces);
            }
            if ov.vpls {
                let marks = overlay::vpl_marks(&frame.camera, &o.selection.shaded, &h.kept, w, ht);
                overlay::draw_marks(&mut bytes, w, ht, &marks);
            }
        }
        if ov.ism {
            if let Some(atlas) = self.ism_atlas(i) {
                overlay::draw_inset(&mut bytes, w, ht, &atlas);
            }
        }
        Some((w, ht, bytes))
    }

    /// Half `i` and the last frame it rendered, if any.
    fn last_output(&self, i: usize) -> Option<(&Half, &FrameOutput)> {
        self.halves
            .get(i)
            .and_then(|h| Some((h, h.output.as_ref()?)))
    }

    /// The VPL marks half `i`'s overlay draws (see [`overlay::vpl_marks`]).
    pub fn vpl_marks(&self, i: usize) -> Vec<overlay::Mark> {
        let Some((h, o)) = self.last_output(i) else {
            return Vec::new();
        };
        let frame = h.pipeline.scene.at(o.time);
        let (w, ht) = (o.image.hdr.width, o.image.hdr.height);
        overlay::vpl_marks(&frame.camera, &o.selection.shaded, &h.kept, w, ht)
    }

    /// The shadow-map faces of half `i`'s last frame (see [`overlay::shadow_faces`]).
    pub fn shadow_faces(&self, i: usize) -> Vec<(glam::Vec3, glam::Vec3, usize)> {
        let Some((h, o)) = self.last_output(i) else {
            return Vec::new();
        };
        let frame = h.pipeline.scene.at(o.time);
        let r = &h.pipeline.renderer.config;
        let samples = frame.emitter_samples(h.pipeline.params.seed, r.light_samples as usize);
        overlay::shadow_faces(&frame, &samples, r.shadow_size, 1.0)
    }

    /// Half `i`'s ISM atlas as the gather last read it (level 0 of the pull-push pyramid, read
    /// back; its first 2^22 texels: 1024 tiles of 64^2), as an image (see
    /// [`overlay::atlas_image`]); None for a classical method (no VPLs) or before the first
    /// frame.
    pub fn ism_atlas(&self, i: usize) -> Option<(u32, u32, Vec<u8>)> {
        let h = self.halves.get(i)?;
        h.output.as_ref()?;
        if h.variant.method != Method::Instant {
            return None;
        }
        let r = &h.pipeline.renderer;
        let size = r.config.ism_size;
        // At most 2^22 texels (16 MB a frame): the first tiles of a large atlas.
        let tiles = r
            .config
            .slots
            .min(((1u64 << 22) / (size as u64 * size as u64)).max(1) as u32);
        let n = tiles as u64 * size as u64 * size as u64;
        let bytes = r.gpu.read_buffer(&r.passes.ism.pyramid, n * 4).ok()?;
        let values: Vec<f32> = bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        Some(overlay::atlas_image(&values, tiles, size))
    }

    /// The `irad render` command line of the frame shown and the settings (left half's
    /// sampler), with `--camera` its camera and `--frames` as [`App::render_frame`] says.
    pub fn command_line(&self) -> String {
        let c = &self.cfg;
        let mut a = vec!["irad".to_string(), "render".to_string()];
        a.push(quote(c.sequence.scene_or(config::DEFAULT_STILL_SCENE)));
        let cam = camera::rounded(&self.shown_camera());
        a.push(format!("--camera {cam}"));
        a.push(format!("--frames {}", self.render_frame()));
        a.push(format!("--size {}", c.sequence.size));
        if c.method != Method::Instant {
            a.push(format!("--method {}", c.method.name()));
        } else {
            a.push(format!("--vpls {}", c.vpls));
            a.push(format!("--sampler {}", c.sampler.kind.name()));
            for k in config::KNOBS.iter() {
                let v = k.get(&c.sampler.knobs);
                if v != k.default() {
                    if let Some(v) = v {
                        a.push(format!("--{} {v}", k.name));
                    }
                }
            }
        }
        let d = config::Render::default();
        if let (Ok(q), Ok(dq)) = (
            serde_json::to_value(&c.quality),
            serde_json::to_value(&d.quality),
        ) {
            if let (Some(q), Some(dq)) = (q.as_object(), dq.as_object()) {
                for (k, v) in q {
                    if dq.get(k) != Some(v) {
                        a.push(format!("--{} {v}", k.replace('_', "-")));
                    }
                }
            }
        }
        if c.exposure != d.exposure {
            a.push(format!("--exposure {}", c.exposure));
        }
        if let Some(cl) = c.clamp {
            a.push(format!("--clamp {cl}"));
        }
        if c.sequence.fps != d.sequence.fps {
            a.push(format!("--fps {}", c.sequence.fps));
        }
        if c.sequence.seed != d.sequence.seed {
            a.push(format!("--seed {}", c.sequence.seed));
        }
        if let Some(e) = &c.sequence.environment {
            a.push(format!("--environment {}", quote(&e.to_string())));
        }
        if c.backend != d.backend {
            a.push(format!(
                "--backend {}",
                format!("{:?}", c.backend).to_lowercase()
            ));
        }
        if c.sequence.allow_outside_paths {
            a.push("--allow-outside-paths".into());
        }
        a.join(" ")
    }

    /// The frame `irad render --frames` is given for the view: the index of the frame shown
    /// when the scene at that frame's time is the scene shown (a still scene, or time and
    /// index in step, as while playing from the start), so that a sampler without history
    /// (uniform, cdf, rejection) renders the same image; else the frame of the current time.
    pub fn render_frame(&self) -> u32 {
        let fps = self.cfg.sequence.fps as f64;
        let (shown, time) = self.shown_frame();
        let in_step = (shown as f64 / fps - time as f64).abs() < 1e-6;
        if self.duration() == 0.0 || in_step {
            shown
        } else {
            (time as f64 * fps).round() as u32
        }
    }

    /// The frame index and time of the frame shown (before the first: those of the next).
    pub fn shown_frame(&self) -> (u32, f32) {
        self.halves
            .first()
            .and_then(|h| h.output.as_ref())
            .map_or((self.index, self.time), |o| (o.index, o.time))
    }

    /// The camera of the frame shown: the user's, or the scene's at the shown frame's time.
    pub fn shown_camera(&self) -> CameraSpec {
        self.camera
            .unwrap_or_else(|| camera::of_scene(&self.scene, self.shown_frame().1))
    }

    /// Writes each half's last frame into the output folder (`cfg.out`) as
    /// `view_NNNN_NAME.exr` and `.png` (NAME the half's sampler, or its method if not instant
    /// radiosity), NNNN the first number not yet used there.
    pub fn save_frame(&self) -> Result<Vec<PathBuf>> {
        let dir = &self.cfg.out;
        std::fs::create_dir_all(dir)
            .map_err(|e| anyhow!("{}: cannot make the folder: {e}", dir.display()))?;
        // Two halves of the same name: _left and _right.
        let names: Vec<String> = self
            .halves
            .iter()
            .enumerate()
            .map(|(i, h)| {
                let name = h.variant.name();
                let twice = self
                    .halves
                    .iter()
                    .filter(|o| o.variant.name() == name)
                    .count()
                    > 1;
                if twice {
                    format!("{name}_{}", ["left", "right"][i.min(1)])
                } else {
                    name.to_string()
                }
            })
            .collect();
        let taken = |n: u32| {
            names
                .iter()
                .any(|name| dir.join(format!("view_{n:04}_{name}.exr")).exists())
        };
        let n = (0..).find(|&n| !taken(n)).expect("a free number");
        let mut out = Vec::new();
        for (h, name) in self.halves.iter().zip(&names) {
            let Some(o) = &h.output else {
                anyhow::bail!("no frame rendered yet to save");
            };
            let stem = dir.join(format!("view_{n:04}_{name}"));
            let exr = stem.with_extension("exr");
            let png = stem.with_extension("png");
            o.image.hdr.write_exr(&exr)?;
            let (w, ht) = (o.image.hdr.width, o.image.hdr.height);
            let img = image::RgbImage::from_raw(w, ht, o.image.ldr.clone()).expect("w*h*3");
            crate::image::write_bytes(&png, &crate::image::encode(&img, image::ImageFormat::Png)?)?;
            out.push(exr);
            out.push(png);
        }
        Ok(out)
    }
}

/// What [`build_halves`] needs: the settings, the halves' variants, the scene and camera, and
/// the frame index and time at which a classical method solves (time NaN: not here).
struct BuildJob {
    gpu: Arc<Gpu>,
    cfg: config::Render,
    variants: Vec<Variant>,
    scene: Scene,
    camera: Option<CameraSpec>,
    at: (u32, f32),
}

/// Builds a renderer per variant; a classical method's renders one frame at `job.at` too, so
/// that its solution is there (the cache keeps it) when the view's step first draws it.
fn build_halves(job: BuildJob) -> Result<Vec<Half>> {
    let mut halves = Vec::new();
    for v in job.variants {
        let mut cfg = job.cfg.clone();
        cfg.sampler.kind = v.sampler;
        cfg.method = v.method;
        let mut scene = job.scene.clone();
        if let Some(c) = &job.camera {
            c.apply(&mut scene)?;
        }
        let mut pipeline = Pipeline::new(job.gpu.clone(), scene, &cfg)?;
        if v.method != Method::Instant && job.at.1.is_finite() {
            pipeline.render_at(job.at.0, job.at.1, false)?;
        }
        halves.push(Half {
            sampler: v.sampler,
            variant: v,
            pipeline,
            output: None,
            flicker: Flicker::default(),
            reference: None,
            kept: Vec::new(),
            seen: None,
        });
    }
    Ok(halves)
}

/// The median of `v` (0 for none).
fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s.get(s.len() / 2).copied().unwrap_or(0.0)
}

/// `size` with height `h` and the width that keeps its aspect (a multiple of 8, at least 8).
fn sized(size: Size, h: u32) -> Size {
    let w = (size.width as f64 * h as f64 / size.height as f64 / 8.0).round() as u32 * 8;
    Size {
        width: w.max(8),
        height: h,
    }
}

/// A word for a shell: quoted when it holds anything but letters, digits and `-_./,:`.
fn quote(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./,:+".contains(c))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

/// Whether two settings render the same (compared as their JSON records).
fn same_settings(a: &config::Render, b: &config::Render) -> bool {
    serde_json::to_value(a).ok() == serde_json::to_value(b).ok()
}

/// Whether `gpu` is a software adapter (llvmpipe, lavapipe).
pub fn is_software(gpu: &Gpu) -> bool {
    gpu.adapter.device_type == format!("{:?}", wgpu::DeviceType::Cpu)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_size_rule_scales_toward_the_target_and_holds_near_it() {
        let mut a = AutoSize::new(true, 512);
        assert_eq!(a.start(true), 128);
        assert_eq!(a.start(false), 512);
        // The first frame after a change is not counted.
        assert_eq!(a.record(128, 10.0, true), None);
        assert_eq!(a.record(128, 0.4, false), None);
        assert_eq!(a.record(128, 0.4, false), None);
        // 4x too slow: half the height.
        assert_eq!(a.record(128, 0.4, false), Some(64));
        // Within 15%: kept.
        for _ in 0..2 {
            assert_eq!(a.record(128, 0.09, false), None);
        }
        assert_eq!(a.record(128, 0.09, false), None);
        // Far too fast: at most twice, at most the room.
        for _ in 0..2 {
            a.record(400, 0.001, false);
        }
        assert_eq!(a.record(400, 0.001, false), Some(512));
    }

    #[test]
    fn flicker_and_heat_map_measure_the_change() {
        let mut a = Hdr::new(2, 1);
        a.data = vec![glam::Vec3::splat(1.0), glam::Vec3::splat(1.0)];
        let mut b = a.clone();
        b.data[0] = glam::Vec3::splat(0.5);
        let (f1, rel, map) = flicker_of(&a, &b);
        assert!(
            (f1 - 0.25).abs() < 1e-6 && (rel - 0.25).abs() < 1e-6,
            "{f1} {rel}"
        );
        assert_eq!(heat_map(&map, 0.5), vec![255, 255, 255, 0, 0, 0]);
        assert_eq!(quote("cornell"), "cornell");
        assert_eq!(quote("my scene.gltf"), "'my scene.gltf'");
    }
}
