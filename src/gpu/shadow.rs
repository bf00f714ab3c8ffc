//! Shadow hemicubes (`shaders/shadow.wgsl`): for every emitter sample, five 90-degree faces
//! (+n, +t, -t, +b, -b) rasterized from the triangles, storing distance to the sample. These
//! are the accurate shadow maps of the direct light. A point light is two samples (two
//! hemicubes, back to back), or, when it lies well outside the geometry, one face zoomed to
//! the frustum that holds the geometry; a spot light is one, drawing only its front face when its cone
//! fits it (within 45 degrees); a directional light draws one orthographic map along its
//! direction over the square that covers the geometry, storing depth along the direction.

use super::bindings::{dynamic_uniform, gpu_struct, Elem, Group, Pass};
use super::common::Tri;
use super::gbuffer::{self, skipped_faces};
use super::Gpu;
use crate::scene::culling::{Clusters, CullView, Instance};
use crate::scene::{EmitterSample, Frame, SampleKind};
use glam::Vec3;
use std::collections::HashMap;

pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

gpu_struct! {
    /// One hemicube face: the eye (a light sample, or for form factors an element's centre),
    /// the face's axes, and the depth range. Shared with `radiosity::hemicube`.
    pub(crate) struct Face {
        pub(crate) pos: [f32; 4],
        pub(crate) right: [f32; 4],
        pub(crate) up: [f32; 4],
        pub(crate) fwd: [f32; 4],
        pub(crate) near: f32,
        pub(crate) far: f32,
        /// Half the width of an orthographic map (0: a perspective face).
        pub(crate) ortho: f32,
        pub(crate) pad1: f32,
    }
}

pub(crate) const PASS: Pass = Pass {
    name: "shadow",
    wgsl: concat!(
        include_str!("../../shaders/texture.wgsl"),
        include_str!("../../shaders/shadow.wgsl")
    ),
    // The texturing data: alpha MASK cut-outs cast no shadow (see `texture.wgsl`).
    groups: &[Group {
        stages: wgpu::ShaderStages::VERTEX_FRAGMENT,
        bindings: &[
            dynamic_uniform("F", &Face::LAYOUT),
            super::bindings::params("cut", &super::surface::Cutouts::LAYOUT),
            super::bindings::read("tris", Elem::Struct(&Tri::LAYOUT)),
            super::bindings::read("attrs", Elem::Struct(&super::surface::TriAttr::LAYOUT)),
            super::bindings::read(
                "materials",
                Elem::Struct(&super::surface::SurfaceMaterial::LAYOUT),
            ),
            super::bindings::read("textures", Elem::Struct(&super::surface::TexInfo::LAYOUT)),
            super::bindings::read("texels", Elem::Plain(4)),
        ],
    }],
};

/// For each of `samples`, the box (lo, hi) around the geometry its light can reach, which
/// its shadow map covers: the triangles in front of an area sample's emitter triangle (one box
/// a triangle, however many samples lie on it) or of a half point light's plane, else the
/// whole frame's; an empty box (lo > hi) if nothing is in front. The shadow map draws only the
/// hemicube faces whose frustum meets it, or one [`Window`] face over it.
pub fn lit_boxes(frame: &Frame, samples: &[EmitterSample]) -> Vec<(Vec3, Vec3)> {
    let mut front: HashMap<u32, (Vec3, Vec3)> = HashMap::new();
    let mut all = None;
    samples
        .iter()
        .map(|s| match (s.kind, s.tri) {
            (SampleKind::Area, Some(t)) => *front.entry(t).or_insert_with(|| {
                frame.bounds_in_front(frame.tris[t as usize][0], frame.normals[t as usize])
            }),
            (SampleKind::PointHalf, _) => frame.bounds_in_front(s.position, s.normal),
            _ => *all.get_or_insert_with(|| frame.bounds()),
        })
        .collect()
}

/// Shadow-map faces a sample needs (of a hemicube's five; they come first): one for a
/// directional light and for a spot whose cone fits the front face, else five.
pub fn faces(s: &EmitterSample) -> usize {
    match s.kind {
        SampleKind::Directional { .. }
        | SampleKind::Environment { .. }
        | SampleKind::PointCone { .. } => 1,
        // The front face holds every direction within 45 degrees of the axis.
        SampleKind::Spot { cos_outer, .. } if cos_outer >= std::f32::consts::FRAC_1_SQRT_2 => 1,
        _ => 5,
    }
}

/// (right, up, forward) of the five hemicube faces around `n`; must match `face_coords` in
/// `shaders/direct.wgsl`.
pub fn face_bases(n: Vec3) -> [(Vec3, Vec3, Vec3); 5] {
    let (t, b) = crate::math::basis(n);
    [(t, b, n), (b, n, t), (b, n, -t), (t, n, b), (t, n, -b)]
}

/// Whether the 90-degree frustum at `eye` along `f` (half-widths along `r` and `u`) can hold
/// a point of the box `(lo, hi)`: false only if the whole box lies behind it or outside one
/// of its four sides (a conservative test: a face it keeps may still see nothing).
pub fn frustum_meets_box(eye: Vec3, (r, u, f): (Vec3, Vec3, Vec3), (lo, hi): (Vec3, Vec3)) -> bool {
    if lo.cmpgt(hi).any() {
        return false;
    }
    let (c, h) = ((lo + hi) * 0.5 - eye, (hi - lo) * 0.5);
    // A margin of a millionth of the box's size keeps a face whose side only touches it.
    let tol = 1e-6 * (h.length() + c.length());
    [f, f - r, f + r, f - u, f + u]
        .iter()
        .all(|m| m.dot(c) + m.abs().dot(h) >= -tol * m.length())
}

/// One shadow face, along a sample's normal, over just the window of its plane (at unit
/// distance along the normal, in the `(t, b)` axes of `math::basis`) that the geometry its
/// light can reach projects into: for an area sample or half a point light whose box lies
/// wholly in front of it and projects into a window no wider than a hemicube face's
/// (2 x 2). It is drawn over the whole map (`texels` = `size` x `size`), so that the window
/// gets at least a hemicube face's resolution, more where the geometry fills less of the
/// sample's view. (A viewport of only as many texels as a hemicube face would give the window
/// cost the same within the noise on lavapipe, in paired runs on the atrium, and left the
/// direct light 25% further from the twin's; `tests/gpu/gpu.rs`.) The face's axes are sheared
/// and scaled so that the raster's x = `((q.t) / (q.n) - centre.x) * scale.x`, as
/// `shaders/direct.wgsl` reads it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    pub centre: glam::Vec2,
    pub scale: glam::Vec2,
    pub texels: glam::UVec2,
}

impl Window {
    /// `s`'s window on a shadow map of `size` x `size` texels over the box `lit` its light
    /// reaches ([`lit_boxes`]), if it has one.
    pub fn of(s: &EmitterSample, lit: (Vec3, Vec3), size: u32) -> Option<Window> {
        if !matches!(s.kind, SampleKind::Area | SampleKind::PointHalf) {
            return None;
        }
        let (lo, hi) = lit;
        if lo.cmpgt(hi).any() {
            return None;
        }
        let (t, b) = crate::math::basis(s.normal);
        let n = s.normal;
        // Every corner well in front of the plane (else the window is unbounded).
        let near = 1e-3 * (hi - lo).length().max(1e-6);
        let (mut wlo, mut whi) = (glam::Vec2::INFINITY, glam::Vec2::NEG_INFINITY);
        for k in 0..8 {
            let c = Vec3::select(glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0), hi, lo)
                - s.position;
            let z = c.dot(n);
            if z < near {
                return None;
            }
            let w = glam::Vec2::new(c.dot(t), c.dot(b)) / z;
            (wlo, whi) = (wlo.min(w), whi.max(w));
        }
        // 1% wider, so that no receiver falls on its edge.
        let half = ((whi - wlo) * 0.505).max(glam::Vec2::splat(1e-4));
        if half.max_element() > 1.0 {
            return None;
        }
        Some(Window {
            centre: (wlo + whi) * 0.5,
            scale: 1.0 / half,
            texels: glam::UVec2::splat(size),
        })
    }

    /// The face's (right, up, forward): `(t - centre.x n) scale.x`, likewise for up.
    fn axes(&self, n: Vec3) -> (Vec3, Vec3, Vec3) {
        let (t, b) = crate::math::basis(n);
        (
            (t - self.centre.x * n) * self.scale.x,
            (b - self.centre.y * n) * self.scale.y,
            n,
        )
    }
}

/// The view of the face with axes `(r, u, f)` at `eye`: in front of its near plane
/// (`f.(p - eye) >= near`) and, unless it is orthographic, inside its four sides
/// (`|r.q|, |u.q| <= f.q` for `q = p - eye`, a thousandth wider).
pub fn face_view((r, u, f): (Vec3, Vec3, Vec3), eye: Vec3, near: f32, ortho: bool) -> CullView {
    let plane = |n: Vec3| (n, -n.dot(eye));
    let (pn, pd) = plane(f);
    let f = f * 1.001;
    CullView {
        near: (pn, pd - near),
        sides: if ortho {
            Vec::new()
        } else {
            vec![plane(f - r), plane(f + r), plane(f - u), plane(f + u)]
        },
    }
}

/// One face a shadow map draws: its layer within the sample's five, the axes to draw it with
/// and the viewport (width, height) it is drawn into.
pub type DrawnFace = (usize, (Vec3, Vec3, Vec3), [u32; 2]);

/// The faces that sample `s`'s shadow map of `size` x `size` texels draws: its [`Window`]'s one
/// face if it has one; else of those its kind needs ([`faces`]), the ones whose
/// frustum meets the geometry its light can reach (a far point light's one face zoomed to its
/// frustum). A receiver's direction always falls in a drawn face.
pub fn drawn_faces(s: &EmitterSample, lit: (Vec3, Vec3), size: u32) -> Vec<DrawnFace> {
    if let Some(w) = Window::of(s, lit, size) {
        return vec![(0, w.axes(s.normal), w.texels.to_array())];
    }
    let zoom = match s.kind {
        SampleKind::PointCone { tan_half } => 1.0 / tan_half,
        _ => 1.0,
    };
    let single = faces(s) == 1;
    face_bases(s.normal)
        .into_iter()
        .take(faces(s))
        .enumerate()
        .filter(|&(_, b)| single || frustum_meets_box(s.position, b, lit))
        .map(|(k, (r, u, f))| (k, (r * zoom, u * zoom, f), [size; 2]))
        .collect()
}

pub struct ShadowMaps {
    pipelines: gbuffer::Pipelines,
    uniform: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    layers: Vec<wgpu::TextureView>,
    pub array_view: wgpu::TextureView,
    depth: wgpu::TextureView,
    pub size: u32,
    /// Bytes from one face's uniform to the next (the adapter's offset alignment).
    stride: u64,
    /// The faces last drawn.
    last: Option<Vec<u8>>,
    /// What the last `encode` drew: faces, triangles over them, of those front faces only
    /// (zero when it kept the maps).
    pub drawn: (u64, u64, u64),
    /// Scenes without cut-outs draw shared corners through an index buffer.
    shared: Option<Shared>,
    /// The spatial clusters each face culls by (`scene::culling::Clusters`): the triangles
    /// are drawn in their order, through `shared`'s indices or, per triangle, through
    /// `vertex_indices` into the renderer's vertices (3 a triangle; the G-buffer draws
    /// through them too).
    clusters: Clusters,
    vertex_indices: wgpu::Buffer,
}

/// The scene's triangles with their corners shared: each distinct position once, and three
/// indices a triangle (built anew whenever the geometry moves), in the drawing order of the
/// clusters ([`ShadowMaps`]).
struct Shared {
    pipelines: gbuffer::Pipelines,
    positions: wgpu::Buffer,
    indices: wgpu::Buffer,
    /// The last upload's corners and indices (empty before the first), by the frame's order.
    corners: (Vec<[f32; 3]>, Vec<u32>),
}

/// Triangles a shadow-map cluster holds (`scene::culling::Clusters`): an instance of more
/// than twice as many is cut into clusters a face culls one by one. On the 187k-triangle
/// bench mesh (`benches/big_mesh.py`), 183 clusters; see docs/design.md, "Big meshes".
pub const CLUSTER: usize = 1024;

/// The distinct corner positions of `tris` (as `[x, y, z]`) and three indices into them a
/// triangle: corners at the same position, bit for bit, are one.
pub fn shared_corners(tris: &[[Vec3; 3]]) -> (Vec<[f32; 3]>, Vec<u32>) {
    let mut index: std::collections::HashMap<[u32; 3], u32> = Default::default();
    let mut positions = Vec::new();
    let indices = tris
        .iter()
        .flatten()
        .map(|p| {
            *index
                .entry(p.to_array().map(f32::to_bits))
                .or_insert_with(|| {
                    positions.push(p.to_array());
                    positions.len() as u32 - 1
                })
        })
        .collect();
    (positions, indices)
}

/// Brings `corners` (positions and indices, as [`shared_corners`] gives them) to `tris`: the
/// shared positions move with their corners, and only if corners that were one have parted
/// (or the triangles are others) are they shared anew, returning true.
pub fn move_corners(corners: &mut (Vec<[f32; 3]>, Vec<u32>), tris: &[[Vec3; 3]]) -> bool {
    let (positions, indices) = corners;
    let kept = indices.len() == 3 * tris.len() && {
        for (&i, p) in indices.iter().zip(tris.iter().flatten()) {
            positions[i as usize] = p.to_array();
        }
        indices
            .iter()
            .zip(tris.iter().flatten())
            .all(|(&i, p)| positions[i as usize] == p.to_array())
    };
    if !kept {
        *corners = shared_corners(tris);
    }
    !kept
}

impl ShadowMaps {
    /// Maps of `size` texels for `samples` emitter samples over a scene of `triangles`
    /// triangles (`cutouts`: whether an alpha MASK cuts any, which needs each fragment's
    /// triangle).
    pub fn new(
        gpu: &Gpu,
        (size, samples): (u32, u32),
        (triangles, cutouts): (u32, bool),
        textures: &super::surface::TextureData,
        tris: &wgpu::Buffer,
    ) -> Self {
        let module = PASS.module(gpu);
        let layout = PASS.groups[0].layout(gpu, PASS.name);
        let attributes = gbuffer::Vertex::ATTRIBUTES;
        let pipelines = gbuffer::Pipelines::new(
            gpu,
            PASS.name,
            (&module, &layout),
            FORMAT,
            gbuffer::Vertex::layout(&attributes),
            ("vs", "fs"),
        );
        let shared = (!cutouts).then(|| {
            let attributes = wgpu::vertex_attr_array![0 => Float32x3];
            let vertices = wgpu::VertexBufferLayout {
                array_stride: 12,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &attributes,
            };
            let corners = 3 * triangles.max(1) as u64;
            Shared {
                pipelines: gbuffer::Pipelines::new(
                    gpu,
                    PASS.name,
                    (&module, &layout),
                    FORMAT,
                    vertices,
                    ("vs_shared", "fs_shared"),
                ),
                positions: gpu.buffer(
                    "shadow corners",
                    12 * corners,
                    wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                ),
                indices: gpu.buffer(
                    "shadow corner indices",
                    4 * corners,
                    wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST,
                ),
                corners: Default::default(),
            }
        });
        let n = (samples * 5).max(1);
        let stride = (std::mem::size_of::<Face>() as u64)
            .next_multiple_of(gpu.limits.min_uniform_buffer_offset_alignment as u64);
        let uniform = gpu.buffer(
            "shadow faces",
            stride * n as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let face = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &uniform,
            offset: 0,
            size: wgpu::BufferSize::new(std::mem::size_of::<Face>() as u64),
        });
        let mut resources = vec![("F", face)];
        resources.extend(textures.resources(tris));
        let bind_group = PASS.groups[0].bind(gpu, PASS.name, &layout, &resources);
        let tex = gbuffer::target(gpu, "shadow maps", size, size, n, FORMAT, true);
        let layers = (0..n)
            .map(|l| {
                tex.create_view(&wgpu::TextureViewDescriptor {
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: l,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        let array_view = tex.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let depth = gbuffer::target(
            gpu,
            "shadow depth",
            size,
            size,
            1,
            wgpu::TextureFormat::Depth32Float,
            false,
        )
        .create_view(&Default::default());
        let vertex_indices = gpu.buffer(
            "cluster vertex indices",
            12 * triangles.max(1) as u64,
            wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST,
        );
        ShadowMaps {
            clusters: Default::default(),
            vertex_indices,
            pipelines,
            uniform,
            bind_group,
            layers,
            array_view,
            depth,
            size,
            stride,
            last: None,
            drawn: (0, 0, 0),
            shared,
        }
    }

    /// The clusters the triangles are drawn in the order of, and the renderer's vertices'
    /// indices in that order (3 a triangle), after the last [`ShadowMaps::upload`].
    pub(crate) fn clusters(&self) -> (&Clusters, &wgpu::Buffer) {
        (&self.clusters, &self.vertex_indices)
    }

    /// Uploads the frame's shared corners (after its geometry moved, or first). The last
    /// frame's sharing is kept if it still holds (every corner at its shared position once the
    /// positions are moved), so a moving scene re-indexes only when corners that met part;
    /// the clusters of `instances` are cut anew then, else their boxes follow the triangles.
    pub fn upload(&mut self, gpu: &Gpu, tris: &[[Vec3; 3]], instances: &[Instance]) {
        let fresh = self.clusters.order.len() != tris.len();
        if fresh {
            self.clusters = Clusters::of(tris, instances, CLUSTER);
        } else {
            self.clusters.refit(tris);
        }
        let order = &self.clusters.order;
        if fresh {
            let ordered: Vec<u32> = order
                .iter()
                .flat_map(|&t| [0, 1, 2].map(|c| 3 * t + c))
                .collect();
            gpu.queue
                .write_buffer(&self.vertex_indices, 0, bytemuck::cast_slice(&ordered));
        }
        let Some(s) = &mut self.shared else {
            return;
        };
        if move_corners(&mut s.corners, tris) || fresh {
            let ordered: Vec<u32> = order
                .iter()
                .flat_map(|&t| {
                    let k = 3 * t as usize;
                    s.corners.1[k..k + 3].iter().copied()
                })
                .collect();
            gpu.queue
                .write_buffer(&s.indices, 0, bytemuck::cast_slice(&ordered));
        }
        gpu.queue
            .write_buffer(&s.positions, 0, bytemuck::cast_slice(&s.corners.0));
    }

    /// Renders the shadow maps of `samples` over the boxes `lit` their light reaches (the faces [`drawn_faces`] gives, face `k` of
    /// sample `j` in layer `5 j + k`) with depth range `(near, far)` for hemicubes,
    /// unless they are the ones last drawn and the geometry did not move. Each face leaves out
    /// what [`CullView::runs`] says of the `instances` (if `cull`; else it draws everything).
    /// Returns whether it drew.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &mut self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        (samples, lit): (&[EmitterSample], &[(Vec3, Vec3)]),
        (near, far): (f32, f32),
        (vertices, tris): (&wgpu::Buffer, u32),
        (instances, cull): (&[Instance], bool),
        geometry_moved: bool,
    ) -> bool {
        let mut bytes = vec![0u8; (self.stride as usize) * samples.len() * 5];
        let mut layers = Vec::new();
        for (j, s) in samples.iter().enumerate() {
            // A punctual light may lie far outside the geometry: its maps reach past it.
            let (near, far, ortho) = match s.kind {
                SampleKind::Directional { extent } => (0.0, 2.0 * extent, extent),
                SampleKind::Environment { extent } => (0.0, s.reach, extent),
                _ => (near, far.max(s.reach * 1.01), 0.0),
            };
            for (k, (r, u, f), viewport) in drawn_faces(s, lit[j], self.size) {
                let face = Face {
                    pos: s.position.extend(1.0).to_array(),
                    right: r.extend(0.0).to_array(),
                    up: u.extend(0.0).to_array(),
                    fwd: f.extend(0.0).to_array(),
                    near,
                    far,
                    ortho,
                    pad1: 0.0,
                };
                let o = (j * 5 + k) * self.stride as usize;
                bytes[o..o + std::mem::size_of::<Face>()]
                    .copy_from_slice(bytemuck::bytes_of(&face));
                let mut view = face_view((r, u, f), s.position, near, ortho > 0.0);
                // An area sample (or half a point light) lights only what lies in front of its
                // plane, and what lies between it and that is in front too: what lies wholly
                // behind the plane (the ceiling around a ceiling light) shadows nothing.
                if matches!(s.kind, SampleKind::Area | SampleKind::PointHalf) {
                    view.sides.push((s.normal, -s.normal.dot(s.position)));
                }
                // The triangles are drawn in their clusters' order.
                let runs = if cull {
                    view.cluster_runs(instances, &self.clusters, tris)
                } else {
                    vec![(0..tris, crate::scene::culling::Draw::All)]
                };
                layers.push((j * 5 + k, viewport, runs, skipped_faces(r, u, f)));
            }
        }
        self.drawn = (0, 0, 0);
        if bytes.is_empty() || (!geometry_moved && self.last.as_ref() == Some(&bytes)) {
            return false;
        }
        for (_, _, runs, _) in &layers {
            let (all, front) = crate::scene::culling::counts(runs);
            self.drawn = (self.drawn.0 + 1, self.drawn.1 + all, self.drawn.2 + front);
        }
        gpu.queue.write_buffer(&self.uniform, 0, &bytes);
        for (l, [w, h], runs, skip) in layers {
            let tile = [((l as u64 * self.stride) as u32, [0, 0, w, h])];
            let target = (&self.layers[l], &self.depth);
            match &self.shared {
                Some(s) => {
                    let mut pass = gbuffer::begin(enc, "shadow face", target.0, target.1);
                    pass.set_bind_group(0, &self.bind_group, &[tile[0].0]);
                    pass.set_viewport(0.0, 0.0, w as f32, h as f32, 0.0, 1.0);
                    pass.set_scissor_rect(0, 0, w, h);
                    pass.set_vertex_buffer(0, s.positions.slice(..));
                    pass.set_index_buffer(s.indices.slice(..), wgpu::IndexFormat::Uint32);
                    s.pipelines.draw(&mut pass, &runs, skip, true);
                }
                None => gbuffer::raster_tiles(
                    enc,
                    "shadow face",
                    &self.bind_group,
                    &tile,
                    target,
                    vertices,
                    |pass| {
                        let b = &self.vertex_indices;
                        pass.set_index_buffer(b.slice(..), wgpu::IndexFormat::Uint32);
                        self.pipelines.draw(pass, &runs, skip, true)
                    },
                ),
            }
        }
        self.last = Some(bytes);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng;
    use crate::scene::{EmitterSample, SampleKind};
    use rand::Rng;

    /// The face `shaders/direct.wgsl`'s `face_coords` reads for direction `l` from a sample
    /// with normal `n`: the largest of the components along (t, b, n).
    fn face_read(n: Vec3, l: Vec3) -> usize {
        let (t, b) = crate::math::basis(n);
        let (x, y, z) = (l.dot(t), l.dot(b), l.dot(n));
        if z >= x.abs() && z >= y.abs() {
            0
        } else if x.abs() >= y.abs() {
            if x > 0.0 {
                1
            } else {
                2
            }
        } else if y > 0.0 {
            3
        } else {
            4
        }
    }

    fn v(r: &mut impl Rng) -> Vec3 {
        Vec3::new(r.random(), r.random(), r.random()) * 2.0 - 1.0
    }

    /// The turn, in normalized device coordinates, of a triangle facing the eye at the origin
    /// and counter-clockwise seen from it, placed along `f`, as `project` in shadow.wgsl maps
    /// it (orthographic: x and y without the division).
    fn ndc_turn((r, u, f): (Vec3, Vec3, Vec3), ortho: bool, rng: &mut impl Rng) -> f32 {
        let c = f.normalize() * 3.0 + (v(rng) * 0.05);
        // Corners around c in the plane facing the eye, counter-clockwise seen from it.
        let (t, b) = crate::math::basis(-c.normalize());
        let tri = [c + t * 0.1, c + b * 0.1, c - t * 0.1 - b * 0.1];
        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
        assert!(n.dot(-c) > 0.0, "the triangle faces the eye");
        let p = tri.map(|q| {
            let (x, y, w) = (q.dot(r), q.dot(u), q.dot(f));
            if ortho {
                glam::Vec2::new(x, y)
            } else {
                glam::Vec2::new(x, y) / w
            }
        });
        (p[1] - p[0]).perp_dot(p[2] - p[0])
    }

    /// `gbuffer::skipped_faces` names the faces that turn clockwise for a triangle facing the
    /// eye (so the pipeline culls those facing away) on every hemicube face (three of the five
    /// mirror), the window faces (which mirror) and the orthographic maps, as shadow.wgsl
    /// projects them; and on the camera's view-projection.
    #[test]
    fn the_faces_skipped_are_the_ones_facing_away_on_every_face() {
        let mut rng = rng(&[41]);
        let mut mirrored = 0;
        for _ in 0..200 {
            let n = v(&mut rng).normalize();
            let mut faces: Vec<((Vec3, Vec3, Vec3), bool)> =
                face_bases(n).into_iter().map(|b| (b, false)).collect();
            faces.extend(face_bases(n).into_iter().map(|b| (b, true)));
            let w = Window {
                centre: glam::Vec2::new(0.3, -0.2),
                scale: glam::Vec2::new(2.0, 3.0),
                texels: glam::UVec2::splat(256),
            };
            faces.push((w.axes(n), false));
            for (axes, ortho) in faces {
                let turn = ndc_turn(axes, ortho, &mut rng);
                let expect = if turn > 0.0 {
                    wgpu::Face::Back
                } else {
                    wgpu::Face::Front
                };
                mirrored += (expect == wgpu::Face::Front) as u32;
                let (r, u, f) = axes;
                assert_eq!(skipped_faces(r, u, f), expect, "{axes:?} ortho {ortho}");
            }
        }
        // Three of each sample's five hemicube faces mirror, perspective or orthographic, and
        // the window face (whose axes are (t, b, n) sheared).
        assert_eq!(mirrored, 200 * 7);
        // The camera: a right-handed view, its front faces keep their turn.
        let cam = crate::scene::Camera::look_at(Vec3::new(1.0, 2.0, 5.0), Vec3::ZERO, Vec3::Y, 0.7);
        let vp = cam.projection(64, 48, 0.01, 100.0) * cam.view();
        let (skip, view) = gbuffer::camera_view(vp, 64, 48);
        assert_eq!(skip, wgpu::Face::Back);
        // Its near plane: the eye behind it, the target in front.
        let g = |p: Vec3| view.near.0.dot(p) + view.near.1;
        assert!(g(cam.position) < 0.0 && g(Vec3::ZERO) > 0.0);
    }

    #[test]
    fn shared_corners_rebuild_every_triangle_and_follow_moving_geometry() {
        let scene = crate::scene::builtin::load("cornell").unwrap().unwrap();
        let f = scene.at(0.0);
        let (positions, indices) = shared_corners(&f.tris);
        assert_eq!(indices.len(), 3 * f.tris.len());
        for (t, ix) in f.tris.iter().zip(indices.chunks(3)) {
            for (p, &i) in t.iter().zip(ix) {
                assert_eq!(Vec3::from(positions[i as usize]), *p);
            }
        }
        // 36 triangles: 108 corners at 28 distinct positions (the room's 8, the two boxes'
        // 16, the light's 4): each shaded once a face instead of 3.9 times.
        assert_eq!(positions.len(), 28);
        // cornell-box's small box slides and turns: its corners move together, so the
        // sharing holds and only the positions move.
        let scene = crate::scene::builtin::load("cornell-box").unwrap().unwrap();
        let (f0, f1) = (scene.at(0.0), scene.at(1.5));
        let mut corners = shared_corners(&f0.tris);
        let indices = corners.1.clone();
        assert!(!move_corners(&mut corners, &f1.tris));
        assert_eq!(corners.1, indices);
        let rebuilt = |(p, i): &(Vec<[f32; 3]>, Vec<u32>)| -> Vec<[f32; 3]> {
            i.iter().map(|&k| p[k as usize]).collect()
        };
        let want: Vec<[f32; 3]> = f1.tris.iter().flatten().map(|p| p.to_array()).collect();
        assert_eq!(rebuilt(&corners), want);
        // Two triangles that shared a corner part: shared anew.
        let mut two = [
            [Vec3::ZERO, Vec3::X, Vec3::Y],
            [Vec3::ZERO, Vec3::Y, Vec3::Z],
        ];
        let mut corners = shared_corners(&two);
        assert_eq!(corners.0.len(), 4);
        two[1][0] = Vec3::NEG_X;
        assert!(move_corners(&mut corners, &two));
        assert_eq!(corners.0.len(), 5);
        let want: Vec<[f32; 3]> = two.iter().flatten().map(|p| p.to_array()).collect();
        assert_eq!(rebuilt(&corners), want);
    }

    #[test]
    fn every_lit_point_of_the_box_falls_in_a_drawn_face() {
        let mut r = rng(&[31, 7]);
        let (mut culled, mut points, mut windows) = (0, 0, 0);
        for _ in 0..4000 {
            let (a, b) = (v(&mut r) * 3.0, v(&mut r) * 3.0);
            let sample = EmitterSample {
                position: v(&mut r) * 4.0,
                normal: v(&mut r).normalize(),
                radiance: Vec3::ONE,
                kind: SampleKind::Area,
                reach: 0.0,
                tri: None,
            };
            let lit = (a.min(b), a.max(b));
            let drawn: Vec<usize> = drawn_faces(&sample, lit, 256).iter().map(|f| f.0).collect();
            let window = Window::of(&sample, lit, 256);
            culled += 5 - drawn.len();
            windows += window.is_some() as usize;
            for _ in 0..50 {
                let u = Vec3::new(r.random(), r.random(), r.random());
                let p = a.min(b) + u * (a - b).abs();
                let l = p - sample.position;
                if l.dot(sample.normal) <= 0.0 {
                    continue;
                }
                points += 1;
                if let Some(w) = window {
                    // Inside the window, as direct.wgsl maps it to the face's texels.
                    let (t, bb) = crate::math::basis(sample.normal);
                    let z = l.dot(sample.normal);
                    let x = (glam::Vec2::new(l.dot(t), l.dot(bb)) / z - w.centre) * w.scale;
                    assert!(x.abs().max_element() <= 1.0, "{p} at {x} outside {w:?}");
                } else {
                    let k = face_read(sample.normal, l);
                    assert!(
                        drawn.contains(&k),
                        "{p} reads face {k} of {sample:?}, drawn {drawn:?}"
                    );
                }
            }
        }
        // Random boxes miss some faces often enough that the test means something.
        println!("{culled} faces culled, {windows} windows, {points} points");
        assert!(culled > 4000 && windows > 100 && points > 40_000);
    }

    #[test]
    fn a_sample_high_above_a_box_draws_one_face_over_its_window() {
        let s = EmitterSample {
            position: Vec3::new(0.0, 10.0, 0.0),
            normal: Vec3::NEG_Y,
            radiance: Vec3::ONE,
            kind: SampleKind::Area,
            reach: 0.0,
            tri: None,
        };
        let lit = (Vec3::new(-8.0, 0.0, -8.0), Vec3::new(8.0, 1.0, 8.0));
        let faces = drawn_faces(&s, lit, 256);
        assert_eq!(faces.len(), 1);
        // The window: x and z in [-8/9, 8/9] at unit distance, 1% wider: half-width
        // 0.505 * 16/9 = 0.8978, over the whole map.
        let w = Window::of(&s, lit, 256).unwrap();
        assert!(w.centre.abs().max_element() < 1e-6, "{w:?}");
        assert_eq!(w.texels, glam::UVec2::splat(256));
        assert_eq!(faces[0].2, [256, 256]);
        let half = 0.505 * 16.0 / 9.0;
        assert!(
            (w.scale - glam::Vec2::splat(1.0 / half))
                .abs()
                .max_element()
                < 1e-5
        );
        // The sheared axes map the box's corner (8, 1, 8) just inside the raster's edge.
        let (r, u, f) = faces[0].1;
        let q = Vec3::new(8.0, 1.0, 8.0) - s.position;
        let ndc = glam::Vec2::new(q.dot(r), q.dot(u)).abs() / q.dot(f);
        let expected = 8.0 / 9.0 / half;
        assert!(
            (ndc - glam::Vec2::splat(expected)).abs().max_element() < 1e-5,
            "{ndc}"
        );
        // A box reaching past 45 degrees along +x projects wider than a hemicube face: the
        // front face and that side's.
        let wide = (Vec3::new(-8.0, 0.0, -8.0), Vec3::new(11.0, 1.0, 8.0));
        assert_eq!(Window::of(&s, wide, 256), None);
        assert_eq!(drawn_faces(&s, wide, 256).len(), 2);
        assert!(!frustum_meets_box(
            Vec3::ZERO,
            (Vec3::X, Vec3::Y, Vec3::Z),
            (Vec3::new(-1.0, -1.0, -3.0), Vec3::new(1.0, 1.0, -2.0))
        ));
    }
}
