//! Radiosity display pass (`shaders/radiosity.wgsl`): a classical radiosity solution's
//! element mesh rasterized from the camera with Gouraud colours (the radiance interpolated
//! from the vertices, emission included), then resolved into a per-pixel HDR buffer. Its CPU
//! twin is `radiosity::display::render_cpu`. With supersampling (`--aa S`) the mesh is
//! rasterized at S x S sub-samples per pixel and the resolve box-filters them, as the
//! instant-radiosity frame's `resolve` pass does.

use super::bindings::{dynamic_uniform, gpu_struct, read, read_write, texture, Elem, Group, Pass};
use super::{gbuffer::target, Gpu};

fn layout(gpu: &Gpu, label: &str, entries: &[wgpu::BindGroupLayoutEntry]) -> wgpu::BindGroupLayout {
    gpu.device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries,
        })
}
use crate::image::Hdr;
use crate::scene::Frame;
use anyhow::Result;
use glam::{Mat4, Vec3};

/// Float bits in an integer target: Rgba32Float is not renderable on GL.
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Vertex {
    pos: [f32; 3],
    color: [f32; 3],
    normal: [f32; 3],
}

gpu_struct! {
    /// The camera of one sub-sample tile (at a dynamic offset per tile).
    struct RadCamera {
        view_proj: Mat4,
        position: [f32; 4],
    }
}

/// The pass's bindings, all in group 0: the raster's camera (binding 0, vertex and
/// fragment), then the resolve's size, image and output (1 to 3, compute). The layouts
/// below are built from these entries, and the naga test checks them against the shader.
pub(crate) const PASS: Pass = Pass {
    name: "radiosity",
    wgsl: include_str!("../../shaders/radiosity.wgsl"),
    groups: &[Group {
        stages: wgpu::ShaderStages::VERTEX_FRAGMENT.union(wgpu::ShaderStages::COMPUTE),
        bindings: &[
            dynamic_uniform("rad_cam", &RadCamera::LAYOUT),
            read("rad_size", Elem::Plain(4)),
            texture("rad_image", wgpu::TextureViewDimension::D2),
            read_write("rad_out", Elem::Plain(16)),
        ],
    }],
};

/// Layout of bindings `range` of [`PASS`] for `stages`.
fn layout_of(
    gpu: &Gpu,
    label: &str,
    range: std::ops::Range<usize>,
    stages: wgpu::ShaderStages,
) -> wgpu::BindGroupLayout {
    let entries: Vec<_> = range
        .map(|i| PASS.groups[0].bindings[i].layout_entry(i as u32, stages))
        .collect();
    layout(gpu, label, &entries)
}

/// What the pass draws of a solution: its elements as triangles and the reflected radiance
/// at each element's three corners (Gouraud), from `radiosity::display::Shaded`.
#[derive(Clone, Copy)]
pub struct Gouraud<'a> {
    pub elements: &'a Frame,
    pub corners: &'a [[glam::Vec3; 3]],
}

pub struct RadiosityPass {
    width: u32,
    height: u32,
    /// Sub-samples per pixel side: the target holds `aa x aa` tiles of the image (as the
    /// G-buffer's), one camera uniform each at `stride` bytes.
    aa: u32,
    stride: u64,
    raster: wgpu::RenderPipeline,
    camera: wgpu::Buffer,
    raster_group: wgpu::BindGroup,
    color: wgpu::TextureView,
    depth: wgpu::TextureView,
    resolve: wgpu::ComputePipeline,
    resolve_group: wgpu::BindGroup,
    vertices: Option<wgpu::Buffer>,
    count: u32,
    /// The frame's radiance per pixel (vec4, alpha 1 where a surface was hit).
    pub output: wgpu::Buffer,
}

impl RadiosityPass {
    /// The pass at one sample per pixel (its centre).
    pub fn new(gpu: &Gpu, width: u32, height: u32) -> Self {
        Self::with_aa(gpu, width, height, 1)
    }

    /// The pass with `aa x aa` sub-samples per pixel, box-filtered (`aa` >= 1; the caller
    /// checks the sub-sample grid against the adapter, as `renderer::check_config` does).
    pub fn with_aa(gpu: &Gpu, width: u32, height: u32, aa: u32) -> Self {
        let aa = aa.max(1);
        let module = gpu.shader("radiosity", include_str!("../../shaders/radiosity.wgsl"));
        let raster_layout = layout_of(
            gpu,
            "radiosity raster",
            0..1,
            wgpu::ShaderStages::VERTEX_FRAGMENT,
        );
        let attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3];
        let raster = gpu.raster_pipeline_over(
            "radiosity raster",
            &module,
            &raster_layout,
            FORMAT,
            wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<Vertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &attributes,
            },
            ("vs", "fs"),
            None,
        );
        let stride = super::gbuffer::uniform_stride::<RadCamera>(gpu);
        let camera = gpu.buffer(
            "radiosity cameras",
            stride * (aa * aa) as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let raster_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("radiosity raster"),
            layout: &raster_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &camera,
                    offset: 0,
                    size: wgpu::BufferSize::new(std::mem::size_of::<RadCamera>() as u64),
                }),
            }],
        });
        let color = target(gpu, "radiosity", width * aa, height * aa, 1, FORMAT, true)
            .create_view(&Default::default());
        let depth = target(
            gpu,
            "radiosity depth",
            width * aa,
            height * aa,
            1,
            wgpu::TextureFormat::Depth32Float,
            false,
        )
        .create_view(&Default::default());
        let output = gpu.buffer(
            "radiosity output",
            width as u64 * height as u64 * 16,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let size = gpu.buffer(
            "radiosity size",
            16,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        gpu.queue
            .write_buffer(&size, 0, bytemuck::cast_slice(&[width, height, aa, 0u32]));
        // The resolve binds 1..3 (binding 0 is the raster's camera).
        let resolve_layout = layout_of(gpu, "radiosity resolve", 1..4, wgpu::ShaderStages::COMPUTE);
        let resolve =
            gpu.compute_pipeline("radiosity resolve", &module, "resolve", &[&resolve_layout]);
        let resolve_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("radiosity resolve"),
            layout: &resolve_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: size.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&color),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: output.as_entire_binding(),
                },
            ],
        });
        RadiosityPass {
            width,
            height,
            aa,
            stride,
            raster,
            camera,
            raster_group,
            color,
            depth,
            resolve,
            resolve_group,
            vertices: None,
            count: 0,
            output,
        }
    }

    /// Uploads a shaded solution (done once per solve; the camera may move freely after),
    /// emission included.
    pub fn upload<'a>(&mut self, gpu: &Gpu, shaded: impl Into<Gouraud<'a>>) {
        self.upload_with(gpu, shaded, true);
    }

    /// Uploads a shaded solution, with or without the elements' emission (without: when
    /// another pass, such as `compose`, adds the emission).
    pub fn upload_with<'a>(&mut self, gpu: &Gpu, shaded: impl Into<Gouraud<'a>>, emission: bool) {
        let shaded = shaded.into();
        let f = shaded.elements;
        let verts: Vec<Vertex> = (0..f.tris.len())
            .flat_map(|e| {
                let le = if emission {
                    f.emission(e)
                } else {
                    glam::Vec3::ZERO
                };
                let n = f.normals[e].to_array();
                (0..3).map(move |k| (e, k, le, n))
            })
            .map(|(e, k, le, n)| Vertex {
                pos: f.tris[e][k].to_array(),
                color: (shaded.corners[e][k] + le).to_array(),
                normal: n,
            })
            .collect();
        self.count = verts.len() as u32;
        let bytes: &[u8] = bytemuck::cast_slice(&verts);
        let fits = self
            .vertices
            .as_ref()
            .is_some_and(|b| b.size() >= bytes.len() as u64);
        if !fits {
            self.vertices = Some(gpu.buffer(
                "radiosity vertices",
                bytes.len() as u64,
                wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            ));
        }
        if let Some(b) = &self.vertices {
            if !bytes.is_empty() {
                gpu.queue.write_buffer(b, 0, bytes);
            }
        }
    }

    /// Rasterizes the uploaded mesh from `frame`'s camera and resolves it into `output`.
    pub fn encode(&self, gpu: &Gpu, enc: &mut wgpu::CommandEncoder, frame: &Frame) {
        let (lo, hi) = frame.bounds();
        let far = (hi - lo)
            .length()
            .max((frame.camera.position - (lo + hi) * 0.5).length() * 2.0)
            .max(1e-3)
            * 1.5;
        let near = (far * 1e-5).max(1e-3);
        let cam = &frame.camera;
        let view_proj = cam.projection(self.width, self.height, near, far) * cam.view();
        // One camera per tile of the target, each moved to its sub-sample (as the G-buffer's).
        let (s, w, h) = (self.aa, self.width, self.height);
        let mut bytes = vec![0u8; self.stride as usize * (s * s) as usize];
        let mut tiles = Vec::new();
        for j in 0..s {
            for i in 0..s {
                let k = (j * s + i) as usize;
                let u = RadCamera {
                    view_proj: super::gbuffer::jittered(
                        view_proj,
                        super::gbuffer::subsample(i, j, s),
                        w,
                        h,
                    ),
                    position: cam.position.extend(1.0).to_array(),
                };
                let o = k * self.stride as usize;
                bytes[o..o + std::mem::size_of::<RadCamera>()]
                    .copy_from_slice(bytemuck::bytes_of(&u));
                tiles.push(((k as u64 * self.stride) as u32, [i * w, j * h, w, h]));
            }
        }
        gpu.queue.write_buffer(&self.camera, 0, &bytes);
        match &self.vertices {
            Some(v) if self.count > 0 => super::gbuffer::raster_tiles(
                enc,
                "radiosity",
                &self.raster_group,
                &tiles,
                (&self.color, &self.depth),
                v,
                |pass| {
                    pass.set_pipeline(&self.raster);
                    pass.draw(0..self.count, 0..1);
                },
            ),
            // Nothing to draw: the cleared target (no surface anywhere).
            _ => drop(super::gbuffer::begin(
                enc,
                "radiosity",
                &self.color,
                &self.depth,
            )),
        }
        super::dispatch(
            enc,
            "radiosity resolve",
            &self.resolve,
            &[&self.resolve_group],
            (self.width.div_ceil(8), self.height.div_ceil(8), 1),
        );
    }

    /// Renders `frame`'s view of the uploaded solution and reads it back.
    pub fn render(&self, gpu: &Gpu, frame: &Frame) -> Result<Hdr> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        self.encode(gpu, &mut enc, frame);
        gpu.queue.submit([enc.finish()]);
        gpu.wait()?;
        let bytes = gpu.read_buffer(&self.output, self.width as u64 * self.height as u64 * 16)?;
        let v: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
        Ok(Hdr {
            width: self.width,
            height: self.height,
            data: v.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect(),
        })
    }
}
