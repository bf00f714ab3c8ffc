//! `irad view`: the scene rendered continuously in a window, with the same device and passes
//! as `irad render` ([`crate::frame::Pipeline`]), the camera moved with the mouse and keys,
//! and egui's controls beside it (docs/view.md). One file per concern: [`camera`] (orbit, pan,
//! dolly, fly), [`app`] (the state and its update step, no window: what the tests drive),
//! [`panel`] (the controls), [`window`] (winit, the surface, the event loop, screenshots).

pub mod app;
pub mod camera;
pub mod overlay;
pub mod panel;
pub mod reference;
pub mod window;

use crate::config;
use anyhow::{bail, Result};
use std::path::PathBuf;

/// `irad view`'s settings: `irad render`'s, and the window's own.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct View {
    #[cfg_attr(feature = "cli", command(flatten))]
    pub render: config::Render,
    /// Start in the split view: the same camera and time rendered two ways, A (left) and B
    /// (right), each with its own state; each a sampler (instant radiosity with it) or a
    /// method (progressive, hierarchical, stochastic), e.g. `cdf,mh` or `cdf,progressive`
    /// (overrides --sampler and --method)
    #[cfg_attr(feature = "cli", arg(long, value_name = "A,B", value_delimiter = ','))]
    pub split: Vec<String>,
    /// Render N frames, save the window's pixels (controls included) as this PNG and exit
    #[cfg_attr(feature = "cli", arg(long, value_name = "FILE"))]
    pub screenshot: Option<PathBuf>,
    /// The frames rendered before --screenshot is taken
    #[cfg_attr(feature = "cli", arg(long, value_name = "N", default_value_t = View::default().after))]
    pub after: u32,
    /// Render at --size always (else the size follows the measured frame time, at most
    /// --size; see docs/view.md)
    #[cfg_attr(feature = "cli", arg(long))]
    pub fixed_size: bool,
    /// The window's size in pixels, WxH
    #[cfg_attr(feature = "cli", arg(long, value_name = "WxH", default_value_t = View::default().window))]
    pub window: config::Size,
    /// What the halves show at the start: the whole frame, or its direct or indirect light
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = app::Component::Full))]
    pub show: app::Component,
    /// Overlays on at the start (docs/view.md, "Overlays")
    #[cfg_attr(feature = "cli", arg(long, value_enum, value_delimiter = ','))]
    pub overlay: Vec<overlay::Overlay>,
    /// Still frames before each step up in size while nothing moves (0: never refine; see
    /// docs/view.md)
    #[cfg_attr(feature = "cli", arg(long, value_name = "N", default_value_t = View::default().refine_after))]
    pub refine_after: u32,
    /// Where `irad compare` caches its references: the flicker and error against one are shown
    /// when the view's scene, size, camera, fps and seed have one
    #[cfg_attr(feature = "cli", arg(long, value_name = "DIR", default_value_os_t = View::default().cache))]
    pub cache: PathBuf,
}

impl Default for View {
    fn default() -> Self {
        View {
            render: config::Render::default(),
            split: Vec::new(),
            screenshot: None,
            after: 10,
            fixed_size: false,
            window: config::Size {
                width: 1024,
                height: 640,
            },
            show: app::Component::Full,
            overlay: Vec::new(),
            refine_after: 8,
            cache: config::Compare::default().cache,
        }
    }
}

impl View {
    pub fn validate(&self) -> Result<()> {
        self.render.validate()?;
        if !(self.split.is_empty() || self.split.len() == 2) {
            bail!(
                "`split` takes two samplers or methods A,B (left and right), not {}",
                self.split.len()
            );
        }
        for s in &self.split {
            app::Variant::parse(s, &self.render)?;
        }
        config::check::int("`refine_after`", self.refine_after, 0, 100_000)?;
        config::check::int("`after`", self.after, 1, 100_000)?;
        if let Some(p) = &self.screenshot {
            if p.extension().is_none_or(|e| !e.eq_ignore_ascii_case("png")) {
                bail!("`screenshot` {}: the file must end in .png", p.display());
            }
        }
        Ok(())
    }

    /// What the view starts with.
    pub fn start(&self) -> Result<app::Start> {
        let mut render = self.render.clone();
        let mut split = None;
        if let [a, b] = &self.split[..] {
            let a = app::Variant::parse(a, &render)?;
            render.method = a.method;
            render.sampler.kind = a.sampler;
            split = Some(app::Variant::parse(b, &render)?);
        }
        Ok(app::Start {
            render,
            split,
            fixed_size: self.fixed_size,
            refine_after: self.refine_after,
            cache: Some(self.cache.clone()),
            component: self.show,
            overlays: {
                let mut o = overlay::Overlays::default();
                for &k in &self.overlay {
                    o.set(k, true);
                }
                o
            },
        })
    }
}

/// `irad view`: opens the window and runs until it is closed (or the screenshot is taken).
pub fn view(v: &View) -> Result<()> {
    v.validate()?;
    window::run(v)
}
