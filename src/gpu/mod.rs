//! Stage 7: the GPU (wgpu, headless). One module per pass, each beside its WGSL twin in
//! `shaders/`: `gbuffer`, `ism` (splat and pull-push), `gather` and `interleave` (its filter), `shadow` and `direct`,
//! `compose` (emission, sum, exposure and sRGB). `renderer` runs them in order for a frame.

pub(crate) mod bindings;
mod common;
pub mod compose;
pub mod direct;
pub mod downsample;
pub mod gather;
pub mod gbuffer;
pub mod hemicube;
pub mod interleave;
pub mod ism;
pub mod profile;
mod quality;
pub mod radiosity;
pub mod renderer;
pub mod shadow;
pub mod surface;
pub mod temporal;

use anyhow::{anyhow, bail, Result};
use serde::Serialize;

pub use profile::Profiling;
pub use quality::{Compensate, HistoryMode, Quality, MAX_SIZE};
pub use renderer::{graph, GpuFrame, RenderedImage, Renderer, RendererConfig};

/// The shader code every pass shares (structs and helpers), prepended to each pass's WGSL.
pub const COMMON_WGSL: &str = include_str!("../../shaders/common.wgsl");

/// Which backend to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum BackendChoice {
    /// Vulkan, Metal or DX12 if present, else OpenGL (or WGPU_BACKEND)
    Auto,
    Vulkan,
    Gl,
    Metal,
    Dx12,
}

impl BackendChoice {
    fn backends(self) -> wgpu::Backends {
        match self {
            BackendChoice::Auto => wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all()),
            BackendChoice::Vulkan => wgpu::Backends::VULKAN,
            BackendChoice::Gl => wgpu::Backends::GL,
            BackendChoice::Metal => wgpu::Backends::METAL,
            BackendChoice::Dx12 => wgpu::Backends::DX12,
        }
    }
}

/// What `irad info` and run records say about an adapter.
#[derive(Clone, Debug, Serialize)]
pub struct AdapterDesc {
    pub name: String,
    pub backend: String,
    pub device_type: String,
    pub driver: String,
    pub driver_info: String,
}

impl AdapterDesc {
    fn of(info: &wgpu::AdapterInfo) -> Self {
        AdapterDesc {
            name: info.name.clone(),
            backend: format!("{:?}", info.backend),
            device_type: format!("{:?}", info.device_type),
            driver: info.driver.clone(),
            driver_info: info.driver_info.clone(),
        }
    }
}

impl std::fmt::Display for AdapterDesc {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} ({}, {}", self.name, self.backend, self.device_type)?;
        if !self.driver.is_empty() {
            write!(f, ", {} {}", self.driver, self.driver_info)?;
        }
        write!(f, ")")
    }
}

/// A device and queue on the chosen adapter.
pub struct Gpu {
    /// The first validation or device error wgpu reported, returned by the next `wait`.
    errors: std::sync::Arc<std::sync::Mutex<Option<String>>>,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter: AdapterDesc,
    pub limits: wgpu::Limits,
}

fn instance(backends: wgpu::Backends) -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    wgpu::Instance::new(desc)
}

/// Preference order: hardware Vulkan/Metal/DX12, then software ones, then GL.
fn rank(info: &wgpu::AdapterInfo) -> u32 {
    let api = match info.backend {
        wgpu::Backend::Vulkan | wgpu::Backend::Metal | wgpu::Backend::Dx12 => 0,
        _ => 2,
    };
    let hw = match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu | wgpu::DeviceType::VirtualGpu => 1,
        _ => 2,
    };
    api * 10 + hw
}

const NO_ADAPTER: &str =
    "no GPU adapter found that runs compute shaders. On Linux without a GPU install Mesa's \
software drivers: `apt-get install mesa-vulkan-drivers libvulkan1` (lavapipe, Vulkan) or \
`apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri` (llvmpipe, OpenGL through EGL)";

/// Every adapter found, with whether irad can use it, in preference order.
pub fn adapters(choice: BackendChoice) -> Vec<(AdapterDesc, bool)> {
    let inst = instance(choice.backends());
    let mut list = pollster::block_on(inst.enumerate_adapters(choice.backends()));
    list.sort_by_key(|a| rank(&a.get_info()));
    list.iter()
        .map(|a| (AdapterDesc::of(&a.get_info()), usable(a)))
        .collect()
}

fn usable(a: &wgpu::Adapter) -> bool {
    let d = a.get_downlevel_capabilities();
    d.flags.contains(wgpu::DownlevelFlags::COMPUTE_SHADERS)
        && a.limits().max_storage_buffers_per_shader_stage >= 8
        && a.limits().max_compute_workgroup_size_x >= 64
}

thread_local! {
    static DEVICES_OPENED: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// How many devices this thread has opened with [`Gpu::new`] (a command opens one and lends
/// it to every pipeline; tests count with this).
pub fn devices_opened() -> u64 {
    DEVICES_OPENED.with(|c| c.get())
}

/// Mesa's EGL and Vulkan drivers print "XDG_RUNTIME_DIR is invalid or not set" on machines
/// without a desktop session, which reads like an error of irad's. Where the variable is unset
/// or not a folder, point it at a private folder under the temporary directory. Call it at
/// the start of `main`, before any thread starts (it sets an environment variable).
pub fn quiet_mesa_runtime_dir() {
    let ok = std::env::var_os("XDG_RUNTIME_DIR")
        .map(|d| std::path::Path::new(&d).is_dir())
        .unwrap_or(false);
    if ok {
        return;
    }
    let dir = std::env::temp_dir().join(format!("irad-runtime-{}", std::process::id()));
    #[cfg(unix)]
    {
        use std::os::unix::fs::DirBuilderExt;
        let _ = std::fs::DirBuilder::new()
            .recursive(true)
            .mode(0o700)
            .create(&dir);
    }
    #[cfg(not(unix))]
    let _ = std::fs::create_dir_all(&dir);
    if dir.is_dir() {
        std::env::set_var("XDG_RUNTIME_DIR", dir);
    }
}

impl Gpu {
    /// Opens the preferred usable adapter for `choice`. A process opens one and shares it
    /// (`Arc<Gpu>`) with every pipeline.
    pub fn new(choice: BackendChoice) -> Result<Gpu> {
        Ok(Self::open(&instance(choice.backends()), choice, None)?.0)
    }

    /// Opens the preferred usable adapter for `choice` that can also present to `window` (an
    /// interactive view): the instance is told the display (`display`, e.g. winit's
    /// `OwnedDisplayHandle`, which GL needs), and the surface comes back with the device and
    /// what the surface takes on that adapter.
    pub fn for_window(
        choice: BackendChoice,
        display: Box<dyn wgpu::wgt::WgpuHasDisplayHandle>,
        window: impl Into<wgpu::SurfaceTarget<'static>>,
    ) -> Result<(Gpu, wgpu::Surface<'static>, wgpu::SurfaceCapabilities)> {
        let mut desc = wgpu::InstanceDescriptor::new_with_display_handle(display);
        desc.backends = choice.backends();
        let inst = wgpu::Instance::new(desc);
        let surface = inst
            .create_surface(window)
            .map_err(|e| anyhow!("cannot make a drawing surface for the window: {e}"))?;
        let (gpu, adapter) = Self::open(&inst, choice, Some(&surface))?;
        let caps = surface.get_capabilities(&adapter);
        Ok((gpu, surface, caps))
    }

    fn open(
        inst: &wgpu::Instance,
        choice: BackendChoice,
        surface: Option<&wgpu::Surface>,
    ) -> Result<(Gpu, wgpu::Adapter)> {
        // The library's own unit tests have no `main` to quiet Mesa first.
        #[cfg(test)]
        {
            static QUIET: std::sync::Once = std::sync::Once::new();
            QUIET.call_once(quiet_mesa_runtime_dir);
        }
        DEVICES_OPENED.with(|c| c.set(c.get() + 1));
        let mut list = pollster::block_on(inst.enumerate_adapters(choice.backends()));
        list.sort_by_key(|a| rank(&a.get_info()));
        let presents = |a: &wgpu::Adapter| surface.is_none_or(|s| a.is_surface_supported(s));
        let Some(adapter) = list.into_iter().find(|a| usable(a) && presents(a)) else {
            if surface.is_some() {
                bail!("no usable {choice:?} adapter can draw to the window ({NO_ADAPTER})");
            }
            if choice == BackendChoice::Auto {
                bail!(NO_ADAPTER);
            }
            bail!("no usable {choice:?} adapter found ({NO_ADAPTER})");
        };
        let al = adapter.limits();
        // What irad needs, raised to what the adapter offers where sizes scale with the job.
        let limits = wgpu::Limits {
            max_storage_buffers_per_shader_stage: al.max_storage_buffers_per_shader_stage.min(8),
            max_storage_buffer_binding_size: al.max_storage_buffer_binding_size,
            max_buffer_size: al.max_buffer_size,
            max_texture_dimension_2d: al.max_texture_dimension_2d,
            max_texture_array_layers: al.max_texture_array_layers,
            max_compute_workgroups_per_dimension: al.max_compute_workgroups_per_dimension,
            max_uniform_buffer_binding_size: al.max_uniform_buffer_binding_size.min(1 << 16),
            ..wgpu::Limits::downlevel_defaults()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("irad"),
            required_limits: limits.clone(),
            required_features: adapter.features() & profile::TIMESTAMP_FEATURES,
            ..Default::default()
        }))
        .map_err(|e| anyhow!("cannot open a device on {}: {e}", adapter.get_info().name))?;
        let errors = std::sync::Arc::new(std::sync::Mutex::new(None));
        let slot = errors.clone();
        device.on_uncaptured_error(std::sync::Arc::new(move |e: wgpu::Error| {
            let mut s = slot.lock().unwrap_or_else(|p| p.into_inner());
            s.get_or_insert_with(|| e.to_string());
        }));
        let gpu = Gpu {
            errors,
            device,
            queue,
            adapter: AdapterDesc::of(&adapter.get_info()),
            limits,
        };
        Ok((gpu, adapter))
    }

    /// Builds a compute or render shader module from a pass's WGSL (with the common code).
    pub fn shader(&self, label: &str, src: &str) -> wgpu::ShaderModule {
        let code = format!("{COMMON_WGSL}\n{src}");
        self.device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(code.into()),
            })
    }

    /// Blocks until the queue is idle.
    pub fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| anyhow!("GPU wait failed: {e}"))?;
        if let Some(e) = self.errors.lock().unwrap_or_else(|p| p.into_inner()).take() {
            bail!("GPU error on {}: {e}", self.adapter);
        }
        Ok(())
    }

    /// Reads a buffer back (it must have COPY_SRC usage).
    pub fn read_buffer(&self, src: &wgpu::Buffer, size: u64) -> Result<Vec<u8>> {
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(src, 0, &staging, 0, size);
        self.queue.submit([enc.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        staging.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        self.wait()?;
        rx.recv()
            .map_err(|_| anyhow!("readback callback dropped"))?
            .map_err(|e| anyhow!("readback failed: {e}"))?;
        let data = staging
            .get_mapped_range(..)
            .map_err(|e| anyhow!("readback map failed: {e:?}"))?
            .to_vec();
        staging.unmap();
        Ok(data)
    }
}

/// Checks that a storage buffer of `bytes` fits the device, with a message saying what to lower.
pub fn check_size(limits: &wgpu::Limits, what: &str, bytes: u64, hint: &str) -> Result<()> {
    let max = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    if bytes > max {
        bail!("{what} needs {bytes} bytes but the adapter allows {max} per buffer: {hint}");
    }
    Ok(())
}

impl Gpu {
    pub fn buffer(&self, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: size.max(16).next_multiple_of(16),
            usage,
            mapped_at_creation: false,
        })
    }

    /// A compute pipeline from a pass's WGSL, entry point and bind group layouts.
    pub(crate) fn compute_pipeline(
        &self,
        label: &str,
        module: &wgpu::ShaderModule,
        entry: &str,
        layouts: &[&wgpu::BindGroupLayout],
    ) -> wgpu::ComputePipeline {
        self.compute_pipeline_with(label, module, entry, layouts, Default::default())
    }

    /// [`Gpu::compute_pipeline`] with its compilation options (e.g. no zeroing of workgroup
    /// memory for a shader that writes all of it before reading).
    pub(crate) fn compute_pipeline_with(
        &self,
        label: &str,
        module: &wgpu::ShaderModule,
        entry: &str,
        layouts: &[&wgpu::BindGroupLayout],
        compilation_options: wgpu::PipelineCompilationOptions,
    ) -> wgpu::ComputePipeline {
        let layouts: Vec<Option<&wgpu::BindGroupLayout>> =
            layouts.iter().map(|l| Some(*l)).collect();
        let pl = self
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: &layouts,
                immediate_size: 0,
            });
        self.device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(&pl),
                module,
                entry_point: Some(entry),
                compilation_options,
                cache: None,
            })
    }

    /// A render pipeline over the scene's vertex buffer (position, triangle index), writing
    /// one colour target and depth.
    pub(crate) fn raster_pipeline(
        &self,
        label: &str,
        module: &wgpu::ShaderModule,
        layout: &wgpu::BindGroupLayout,
        target: wgpu::TextureFormat,
    ) -> wgpu::RenderPipeline {
        let attributes = gbuffer::Vertex::ATTRIBUTES;
        self.raster_pipeline_over(
            label,
            module,
            layout,
            target,
            gbuffer::Vertex::layout(&attributes),
            ("vs", "fs"),
            None,
        )
    }

    /// A render pipeline (entry points `(vs, fs)`, skipping the faces `cull` names, depth
    /// test `Less` on a Depth32Float target) over vertices laid out as `vertices`, writing one
    /// colour target.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn raster_pipeline_over(
        &self,
        label: &str,
        module: &wgpu::ShaderModule,
        layout: &wgpu::BindGroupLayout,
        target: wgpu::TextureFormat,
        vertices: wgpu::VertexBufferLayout,
        (vs, fs): (&str, &str),
        cull: Option<wgpu::Face>,
    ) -> wgpu::RenderPipeline {
        let pl = self
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: &[Some(layout)],
                immediate_size: 0,
            });
        self.device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&pl),
                vertex: wgpu::VertexState {
                    module,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers: &[Some(vertices)],
                },
                primitive: wgpu::PrimitiveState {
                    cull_mode: cull,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: wgpu::TextureFormat::Depth32Float,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &[Some(target.into())],
                }),
                multiview_mask: None,
                cache: None,
            })
    }
}

/// Workgroup counts for `n` invocations of a 1D kernel of 64, split over y past the limit
/// (the shaders index `x + y * 65535 * 64`).
pub(crate) fn groups_1d(n: u64) -> (u32, u32) {
    let g = n.div_ceil(64);
    if g <= 65535 {
        (g.max(1) as u32, 1)
    } else {
        (65535, g.div_ceil(65535) as u32)
    }
}

/// Runs a compute pipeline with bind groups as one submission.
pub(crate) fn dispatch(
    enc: &mut wgpu::CommandEncoder,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    groups: &[&wgpu::BindGroup],
    xyz: (u32, u32, u32),
) {
    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: None,
    });
    pass.set_pipeline(pipeline);
    for (i, g) in groups.iter().enumerate() {
        pass.set_bind_group(i as u32, *g, &[]);
    }
    pass.dispatch_workgroups(xyz.0, xyz.1, xyz.2);
}

/// A compute pass with one invocation per pixel (8x8 workgroups) and one bind group: the
/// shape of the gather, direct and compose passes.
pub(crate) struct PixelPass {
    label: &'static str,
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
}

impl PixelPass {
    /// The pass `pass` (one bind group) over `resources`, named as in its table.
    pub(crate) fn new(
        gpu: &Gpu,
        pass: &'static bindings::Pass,
        resources: &[(&str, wgpu::BindingResource)],
    ) -> Self {
        let module = pass.module(gpu);
        let layouts = pass.layouts(gpu);
        PixelPass {
            label: pass.name,
            pipeline: gpu.compute_pipeline(pass.name, &module, "main", &[&layouts[0]]),
            group: pass.groups[0].bind(gpu, pass.name, &layouts[0], resources),
        }
    }

    pub(crate) fn encode(&self, enc: &mut wgpu::CommandEncoder, width: u32, height: u32) {
        dispatch(
            enc,
            self.label,
            &self.pipeline,
            &[&self.group],
            (width.div_ceil(8), height.div_ceil(8), 1),
        );
    }
}
