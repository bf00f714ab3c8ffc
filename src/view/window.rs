//! The window: winit's event loop, a wgpu surface on the same device the halves render on,
//! egui drawn over it through egui-wgpu, and `--screenshot` (the window's pixels, controls
//! included, read back from the same drawing made into a texture of its own).

use super::app::{App, AutoSize, Input};
use super::View;
use crate::gpu::Gpu;
use anyhow::{anyhow, bail, Context as _, Result};
use std::sync::Arc;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

/// The display the environment names, or an error saying there is none.
pub fn display() -> Result<String> {
    let var = |k: &str| std::env::var(k).ok().filter(|v| !v.is_empty());
    match (var("WAYLAND_DISPLAY"), var("DISPLAY")) {
        (Some(w), _) => Ok(format!("Wayland display {w}")),
        (None, Some(x)) => Ok(format!("X display {x}")),
        (None, None) => bail!(
            "irad view needs a display, and neither DISPLAY nor WAYLAND_DISPLAY is set (run it in a desktop session, over `ssh -X`, or under `xvfb-run -a`; `irad render` writes frames without one)"
        ),
    }
}

/// Opens the window and runs the view until it is closed, Esc is pressed, or the screenshot
/// is written.
pub fn run(v: &View) -> Result<()> {
    let display = display()?;
    // winit panics on some failures it could report; keep those an error too.
    let event_loop = std::panic::catch_unwind(EventLoop::new)
        .map_err(|_| anyhow!("cannot connect to the {display}"))?
        .map_err(|e| anyhow!("cannot connect to the {display}: {e}"))?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut handler = Handler {
        view: v.clone(),
        display,
        running: None,
        pending: Vec::new(),
        frames: 0,
        result: None,
    };
    event_loop
        .run_app(&mut handler)
        .map_err(|e| anyhow!("the window's event loop failed: {e}"))?;
    handler.result.unwrap_or(Ok(()))
}

struct Handler {
    view: View,
    display: String,
    running: Option<Running>,
    pending: Vec<Input>,
    /// Frames rendered so far.
    frames: u32,
    /// Set when the view ends (Ok after a screenshot or a close, Err on a failure).
    result: Option<Result<()>>,
}

struct Running {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    egui: egui::Context,
    state: egui_winit::State,
    painter: egui_wgpu::Renderer,
    app: App,
    textures: Vec<egui::TextureHandle>,
}

impl Handler {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        if self.result.is_none() {
            self.result = Some(Err(e));
        }
        event_loop.exit();
    }

    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<Running> {
        let size = self.view.window;
        let attrs = Window::default_attributes()
            .with_title("irad view")
            .with_inner_size(winit::dpi::PhysicalSize::new(size.width, size.height));
        let window = Arc::new(
            event_loop
                .create_window(attrs)
                .map_err(|e| anyhow!("cannot open a window on the {}: {e}", self.display))?,
        );
        let (gpu, surface, caps) = Gpu::for_window(
            self.view.render.backend,
            Box::new(event_loop.owned_display_handle()),
            window.clone(),
        )?;
        // egui draws in gamma space: a non-sRGB format where there is one.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| !f.is_srgb())
            .or(caps.formats.first().copied())
            .ok_or_else(|| anyhow!("the window's surface offers no format"))?;
        let inner = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: inner.width.max(1),
            height: inner.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes.first().copied().unwrap_or_default(),
            view_formats: vec![],
        };
        surface.configure(&gpu.device, &config);
        let egui = egui::Context::default();
        let state = egui_winit::State::new(
            egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(gpu.limits.max_texture_dimension_2d as usize),
        );
        let painter = egui_wgpu::Renderer::new(&gpu.device, format, Default::default());
        let gpu = Arc::new(gpu);
        let mut start = self.view.start()?;
        if !start.fixed_size {
            // The room for the images: the window less the panel, at most --size.
            let h = start.render.sequence.size.height.min(room(inner.height));
            start.render.sequence.size.width =
                (start.render.sequence.size.width * h / start.render.sequence.size.height).max(8);
            start.render.sequence.size.height = h;
        }
        let mut app = App::new(gpu, &start)?;
        // Settings' rebuilds off the window's thread (the first build above is on it).
        app.background = true;
        eprintln!(
            "irad view: {} on {} ({}), window {}x{}",
            app.cfg
                .sequence
                .scene_or(crate::config::DEFAULT_STILL_SCENE),
            app.gpu.adapter.name,
            app.gpu.adapter.backend,
            config.width,
            config.height
        );
        Ok(Running {
            window,
            surface,
            config,
            egui,
            state,
            painter,
            app,
            textures: Vec::new(),
        })
    }

    /// One frame: apply what was asked, render the halves, draw the controls, present; and
    /// the screenshot when it is due. Returns whether the view should end.
    fn frame(&mut self) -> Result<bool> {
        let r = self.running.as_mut().expect("open");
        for input in self.pending.drain(..) {
            if let Err(e) = r.app.apply(input) {
                r.app.message = format!("refused: {e:#}");
            }
        }
        r.app.step()?;
        self.frames += 1;
        // The halves' images into egui textures.
        r.textures.truncate(r.app.halves.len());
        for i in 0..r.app.halves.len() {
            let Some((w, h, rgb)) = r.app.shown(i) else {
                continue;
            };
            let img = egui::ColorImage::from_rgb([w as usize, h as usize], &rgb);
            let opts = egui::TextureOptions::LINEAR;
            match r.textures.get_mut(i) {
                Some(t) => t.set(img, opts),
                None => r
                    .textures
                    .push(r.egui.load_texture(format!("half{i}"), img, opts)),
            }
        }
        let raw = r.state.take_egui_input(&r.window);
        let mut asked = (Vec::new(), false);
        // `C`'s text onto the clipboard (egui-winit's: X11 or Wayland; where there is none it
        // only logs, and the text is on stdout and in the panel anyway).
        let mut clip = r.app.clipboard.take();
        let out = r.egui.run_ui(raw, |ui| {
            if let Some(text) = clip.take() {
                ui.ctx().copy_text(text);
            }
            asked = super::panel::ui(ui, &r.app, &r.textures);
        });
        r.state
            .handle_platform_output(&r.window, out.platform_output);
        let jobs = r.egui.tessellate(out.shapes, out.pixels_per_point);
        let gpu = r.app.gpu.clone();
        for (id, deltas) in &out.textures_delta.set {
            for delta in deltas {
                r.painter
                    .update_texture(&gpu.device, &gpu.queue, *id, delta);
            }
        }
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [r.config.width, r.config.height],
            pixels_per_point: out.pixels_per_point,
        };
        let target = match r.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => Some(t),
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                r.surface.configure(&gpu.device, &r.config);
                None
            }
            _ => None,
        };
        let shot_due = self.view.screenshot.is_some() && self.frames >= self.view.after;
        if let Some(t) = target {
            let view = t.texture.create_view(&Default::default());
            paint(&gpu, &mut r.painter, &view, &jobs, &screen);
            gpu.queue.present(t);
        }
        if shot_due {
            let path = self.view.screenshot.clone().expect("due");
            let pixels = capture(&gpu, &mut r.painter, r.config.format, &jobs, &screen)?;
            crate::image::write_bytes(
                &path,
                &crate::image::encode(&pixels, image::ImageFormat::Png)?,
            )?;
            crate::outln!(
                "wrote {} ({}x{}, after {} frames at render size {}: {:.1} fps, {:.0} ms a frame of which {:.0} ms rendering)",
                path.display(),
                pixels.width(),
                pixels.height(),
                self.frames,
                r.app.cfg.sequence.size,
                1.0 / r.app.frame_seconds.max(1e-9),
                r.app.frame_seconds * 1e3,
                r.app.render_seconds * 1e3,
            )?;
            let stages: Vec<String> = r
                .app
                .stage_medians()
                .iter()
                .filter(|(_, t)| *t > 0.0)
                .map(|(n, t)| format!("{n} {:.2}", t * 1e3))
                .collect();
            crate::outln!(
                "stages, median of the last {} frames, summed over {} (ms): {}",
                r.app.render_samples(),
                if r.app.halves.len() == 1 {
                    "the view"
                } else {
                    "both halves"
                },
                stages.join(", ")
            )?;
        }
        for id in &out.textures_delta.free {
            r.painter.free_texture(id);
        }
        self.pending.extend(asked.0);
        Ok(asked.1 || shot_due)
    }
}

impl ApplicationHandler for Handler {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_some() || self.result.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(r) => {
                r.window.request_redraw();
                self.running = Some(r);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(r) = self.running.as_mut() else {
            return;
        };
        let _ = r.state.on_window_event(&r.window, &event);
        match event {
            WindowEvent::CloseRequested => {
                self.result.get_or_insert(Ok(()));
                event_loop.exit();
            }
            WindowEvent::Resized(s) => {
                r.config.width = s.width.max(1);
                r.config.height = s.height.max(1);
                r.surface.configure(&r.app.gpu.device, &r.config);
                // The size rule's room follows the window (at most --size).
                let most = self.view.render.sequence.size.height;
                if let Some(a) = &mut r.app.auto {
                    a.max_height = room(s.height).min(most);
                }
            }
            WindowEvent::RedrawRequested => match self.frame() {
                Ok(true) => {
                    self.result.get_or_insert(Ok(()));
                    event_loop.exit();
                }
                Ok(false) => {}
                Err(e) => self.fail(event_loop, e),
            },
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        if let Some(r) = &self.running {
            r.window.request_redraw();
        }
    }
}

/// The render height a window `height` pixels high has room for (less the labels, the
/// flicker and the stages' table below the images; see `panel::images`).
fn room(height: u32) -> u32 {
    let h = height as f32;
    ((h - 230.0).max(0.5 * h) as u32).max(AutoSize::MIN_HEIGHT)
}

/// Draws egui's `jobs` into `target` (cleared first).
fn paint(
    gpu: &Gpu,
    painter: &mut egui_wgpu::Renderer,
    target: &wgpu::TextureView,
    jobs: &[egui::ClippedPrimitive],
    screen: &egui_wgpu::ScreenDescriptor,
) {
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    let extra = painter.update_buffers(&gpu.device, &gpu.queue, &mut enc, jobs, screen);
    {
        let pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("egui"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                resolve_target: None,
                depth_slice: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        painter.render(&mut pass.forget_lifetime(), jobs, screen);
    }
    gpu.queue.submit(extra.into_iter().chain([enc.finish()]));
}

/// The window's pixels: the same drawing made into a texture that can be read back.
fn capture(
    gpu: &Gpu,
    painter: &mut egui_wgpu::Renderer,
    format: wgpu::TextureFormat,
    jobs: &[egui::ClippedPrimitive],
    screen: &egui_wgpu::ScreenDescriptor,
) -> Result<image::RgbImage> {
    let [w, h] = screen.size_in_pixels;
    let tex = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("screenshot"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    paint(
        gpu,
        painter,
        &tex.create_view(&Default::default()),
        jobs,
        screen,
    );
    let row =
        (w * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let size = row as u64 * h as u64;
    let buf = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("screenshot"),
        size,
        usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    enc.copy_texture_to_buffer(
        tex.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buf,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(h),
            },
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    gpu.queue.submit([enc.finish()]);
    let bytes = gpu
        .read_buffer(&buf, size)
        .context("reading the screenshot back")?;
    let bgra = matches!(
        format,
        wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
    );
    let rgba = matches!(
        format,
        wgpu::TextureFormat::Rgba8Unorm | wgpu::TextureFormat::Rgba8UnormSrgb
    );
    if !(bgra || rgba) {
        bail!("cannot save a screenshot of a {format:?} window surface");
    }
    let mut rgb = Vec::with_capacity((w * h * 3) as usize);
    for y in 0..h as usize {
        for px in bytes[y * row as usize..][..w as usize * 4].chunks_exact(4) {
            if bgra {
                rgb.extend([px[2], px[1], px[0]]);
            } else {
                rgb.extend([px[0], px[1], px[2]]);
            }
        }
    }
    Ok(image::RgbImage::from_raw(w, h, rgb).expect("w*h*3"))
}
