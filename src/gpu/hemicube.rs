//! The hemicube pass (`shaders/hemicube.wgsl`): from a point, the elements given are
//! rasterized, each with its index, into the five faces of a unit hemicube, and the delta
//! form factors of the pixels each element covers are summed into a row of form factors.
//! Its derivation and measured error are in `src/radiosity/hemicube.rs`, where the classical
//! solvers' meshes are loaded into it.

use super::bindings::{dynamic_uniform, Group, Pass};
use super::shadow::Face;
use super::{gbuffer, Gpu};
use anyhow::{bail, Result};
use glam::Vec3;

const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

/// The pass's binding: one face at a dynamic offset into a buffer of five (the same face
/// struct as the shadow hemicubes').
pub(crate) const PASS: Pass = Pass {
    name: "hemicube",
    wgsl: include_str!("../../shaders/hemicube.wgsl"),
    groups: &[Group {
        stages: wgpu::ShaderStages::VERTEX,
        bindings: &[dynamic_uniform("H", &Face::LAYOUT)],
    }],
};

/// (right, up, forward) of the five faces around `n`: the top face, then the sides along
/// +t, -t, +b, -b. Every triple has right x up = forward (the shader's winding test needs it).
pub fn face_bases(n: Vec3) -> [(Vec3, Vec3, Vec3); 5] {
    let (t, b) = crate::math::basis(n);
    [(t, b, n), (b, n, t), (-b, n, -t), (-t, n, b), (t, n, -b)]
}

/// Delta form factors of the five faces, `5 * R * R` values, face-major then row by row
/// (row 0 at the top of the face, as the target stores it). The lower halves of the side
/// faces, below the eye's plane, weigh 0.
pub fn delta_factors(r: u32) -> Vec<f32> {
    let r = r as usize;
    let d = 2.0 / r as f64;
    let da = d * d;
    let pi = std::f64::consts::PI;
    let mut w = vec![0.0f32; 5 * r * r];
    for row in 0..r {
        // Screen y grows downwards; the face's up axis grows upwards.
        let y = 1.0 - (row as f64 + 0.5) * d;
        for col in 0..r {
            let x = -1.0 + (col as f64 + 0.5) * d;
            let top = da / (pi * (x * x + y * y + 1.0).powi(2));
            w[row * r + col] = top as f32;
            if y > 0.0 {
                let side = y * da / (pi * (x * x + y * y + 1.0).powi(2));
                for k in 1..5 {
                    w[k * r * r + row * r + col] = side as f32;
                }
            }
        }
    }
    w
}

/// A mesh loaded for hemicubes of one resolution: its elements in a vertex buffer (each
/// vertex carrying its element's index), five face targets and their read-back buffer.
pub struct Hemicube {
    pub resolution: u32,
    elements: usize,
    pipeline: wgpu::RenderPipeline,
    uniform: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    texture: wgpu::Texture,
    layers: Vec<wgpu::TextureView>,
    depth: wgpu::TextureView,
    vertices: wgpu::Buffer,
    readback: wgpu::Buffer,
    /// Bytes per row of the read-back (padded to the copy alignment).
    row_bytes: u32,
    stride: u64,
    /// Depth range: the mesh's bounding-box diagonal bounds every distance.
    far: f32,
    weights: Vec<f32>,
}

impl Hemicube {
    /// Loads `elements` (each its corners and unit normal) for hemicubes of `resolution`
    /// pixels across a full face (even, at least 2, at most the adapter's texture size).
    pub fn new(gpu: &Gpu, elements: &[([Vec3; 3], Vec3)], resolution: u32) -> Result<Hemicube> {
        let max = gpu.limits.max_texture_dimension_2d;
        if resolution < 2 || !resolution.is_multiple_of(2) || resolution > max {
            bail!(
                "hemicube resolution {resolution} must be even and between 2 and {max} \
                 (the adapter's texture size)"
            );
        }
        if elements.len() >= u32::MAX as usize {
            bail!(
                "hemicube: {} elements do not fit 32-bit indices",
                elements.len()
            );
        }
        let module = PASS.module(gpu);
        let layout = PASS.groups[0].layout(gpu, "hemicube");
        let pipeline = gpu.raster_pipeline("hemicube", &module, &layout, FORMAT);
        let stride = (std::mem::size_of::<Face>() as u64)
            .next_multiple_of(gpu.limits.min_uniform_buffer_offset_alignment as u64);
        let uniform = gpu.buffer(
            "hemicube faces",
            stride * 5,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let face = wgpu::BufferBinding {
            buffer: &uniform,
            offset: 0,
            size: wgpu::BufferSize::new(std::mem::size_of::<Face>() as u64),
        };
        let bind_group = PASS.groups[0].bind(
            gpu,
            "hemicube",
            &layout,
            &[("H", wgpu::BindingResource::Buffer(face))],
        );
        let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("hemicube faces"),
            size: wgpu::Extent3d {
                width: resolution,
                height: resolution,
                depth_or_array_layers: 5,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let layers = (0..5)
            .map(|l| {
                texture.create_view(&wgpu::TextureViewDescriptor {
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: l,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        let depth = gbuffer::target(
            gpu,
            "hemicube depth",
            resolution,
            resolution,
            1,
            wgpu::TextureFormat::Depth32Float,
            false,
        )
        .create_view(&Default::default());
        // Each element wound counter-clockwise around its normal (the shader tells fronts
        // from backs by winding).
        let mut verts = Vec::with_capacity(elements.len() * 3);
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for (e, &([a, mut b, mut c], normal)) in elements.iter().enumerate() {
            if (b - a).cross(c - a).dot(normal) < 0.0 {
                std::mem::swap(&mut b, &mut c);
            }
            for p in [a, b, c] {
                lo = lo.min(p);
                hi = hi.max(p);
                verts.push(gbuffer::Vertex {
                    pos: p.to_array(),
                    tri: e as u32,
                });
            }
        }
        let vertices = gpu.buffer(
            "hemicube elements",
            (verts.len() * std::mem::size_of::<gbuffer::Vertex>()) as u64,
            wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        );
        gpu.queue
            .write_buffer(&vertices, 0, bytemuck::cast_slice(&verts));
        let far = if elements.is_empty() {
            1.0
        } else {
            2.0 * (hi - lo).length().max(1e-3)
        };
        let row_bytes = (resolution * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let readback = gpu.buffer(
            "hemicube readback",
            row_bytes as u64 * resolution as u64 * 5,
            wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        );
        Ok(Hemicube {
            resolution,
            elements: elements.len(),
            pipeline,
            uniform,
            bind_group,
            texture,
            layers,
            depth,
            vertices,
            readback,
            row_bytes,
            stride,
            far,
            weights: delta_factors(resolution),
        })
    }

    /// The five faces seen from `x` with unit normal `n`: per pixel, the element index + 1
    /// (0: nothing, or an element's back), face-major, row by row.
    pub fn faces(&self, gpu: &Gpu, x: Vec3, n: Vec3) -> Result<Vec<u32>> {
        let r = self.resolution as usize;
        if self.elements == 0 {
            return Ok(vec![0; 5 * r * r]);
        }
        // Lifted a hair off the surface: elements in the eye's own plane then lie in the
        // side faces' discarded lower halves, not on the horizon row.
        let eye = x + n * (self.far * 1e-6);
        let mut bytes = vec![0u8; self.stride as usize * 5];
        for (k, (right, up, fwd)) in face_bases(n).into_iter().enumerate() {
            let face = Face {
                pos: eye.extend(1.0).to_array(),
                right: right.extend(0.0).to_array(),
                up: up.extend(0.0).to_array(),
                fwd: fwd.extend(0.0).to_array(),
                near: self.far * 1e-6,
                far: self.far,
                ortho: 0.0,
                pad1: 0.0,
            };
            let o = k * self.stride as usize;
            bytes[o..o + std::mem::size_of::<Face>()].copy_from_slice(bytemuck::bytes_of(&face));
        }
        gpu.queue.write_buffer(&self.uniform, 0, &bytes);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        for (k, layer) in self.layers.iter().enumerate() {
            gbuffer::raster(
                &mut enc,
                "hemicube face",
                &self.pipeline,
                &self.bind_group,
                &[(k as u64 * self.stride) as u32],
                layer,
                &self.depth,
                &self.vertices,
                (self.elements * 3) as u32,
            );
        }
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &self.readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.row_bytes),
                    rows_per_image: Some(self.resolution),
                },
            },
            wgpu::Extent3d {
                width: self.resolution,
                height: self.resolution,
                depth_or_array_layers: 5,
            },
        );
        gpu.queue.submit([enc.finish()]);
        let data = gpu.read_buffer(&self.readback, self.row_bytes as u64 * r as u64 * 5)?;
        let mut out = Vec::with_capacity(5 * r * r);
        for row in 0..5 * r {
            let o = row * self.row_bytes as usize;
            out.extend(
                data[o..o + 4 * r]
                    .chunks_exact(4)
                    .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])),
            );
        }
        Ok(out)
    }

    /// The elements loaded.
    pub fn elements(&self) -> usize {
        self.elements
    }

    /// The form factors `F(dA_x -> j)` from a point `x` with unit normal `n` to every element
    /// `j` of the mesh.
    pub fn row_at(&self, gpu: &Gpu, x: Vec3, n: Vec3) -> Result<Vec<f32>> {
        let ids = self.faces(gpu, x, n)?;
        let mut row = vec![0.0f64; self.elements];
        for (&id, &w) in ids.iter().zip(&self.weights) {
            if id > 0 && w > 0.0 {
                row[id as usize - 1] += w as f64;
            }
        }
        Ok(row.into_iter().map(|f| f as f32).collect())
    }

    /// Row `F_i,*` of element `i` (centre `x`, unit normal `n`): the hemicube at its centre
    /// along its normal (`F_ii = 0`).
    pub fn row(&self, gpu: &Gpu, i: usize, x: Vec3, n: Vec3) -> Result<Vec<f32>> {
        if i >= self.elements {
            bail!(
                "hemicube row {i}: the hemicube was built for {} elements",
                self.elements
            );
        }
        let mut row = self.row_at(gpu, x, n)?;
        row[i] = 0.0;
        Ok(row)
    }
}
