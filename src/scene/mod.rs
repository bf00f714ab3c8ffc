//! Stage 1: the scene. A [`Scene`] is what a glTF file describes (meshes, materials, nodes,
//! a camera, animations); [`Scene::at`] evaluates it at a time into a [`Frame`]: world-space
//! triangles, the camera and the emitters.

pub mod anim;
pub mod builtin;
pub mod camera;
pub mod culling;
pub mod environment;
pub mod framing;
pub mod inspect;
pub mod lights;
pub mod load;
mod samples;
pub mod texture;

use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use std::sync::Arc;

/// The largest coordinate irad accepts, in a mesh or in the world: beyond it, squared
/// distances and areas overflow 32-bit floats.
pub const MAX_COORD: f32 = 1e9;

pub use anim::{Channel, Interpolation, Property};
pub use camera::Camera;
pub use environment::Environment;
pub use lights::{LightDef, LightKind, PunctualLight};
pub use samples::{EmitterSample, SampleKind};
pub use texture::{TexRef, Texture};

/// A Lambertian material: albedo `rho` and emitted radiance `Le` (front face only, unless
/// `double_sided`: then [`Scene::at`] adds a back-facing twin of each emitting triangle).
/// At a surface point the albedo is `albedo` times the base colour texture times the
/// vertex colour, the emission `emission` times the emissive texture (see
/// [`Frame::albedo_at`]); `albedo` and `emission` alone are the factors.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub albedo: Vec3,
    pub emission: Vec3,
    /// glTF's doubleSided: an emitting surface emits from both sides.
    pub double_sided: bool,
    /// baseColorTexture: multiplies `albedo` (and its alpha `alpha`).
    pub base_color_texture: Option<TexRef>,
    /// emissiveTexture: multiplies `emission`.
    pub emissive_texture: Option<TexRef>,
    /// baseColorFactor's alpha.
    pub alpha: f32,
    /// alphaMode MASK: where the alpha (factor x texture x vertex colour) is under this
    /// cutoff the surface is not there (no hit, no shadow, no VPL, not drawn).
    pub alpha_cutoff: Option<f32>,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: String::new(),
            albedo: Vec3::ONE,
            emission: Vec3::ZERO,
            double_sided: false,
            base_color_texture: None,
            emissive_texture: None,
            alpha: 1.0,
            alpha_cutoff: None,
        }
    }
}

impl Material {
    /// Whether this emits from both sides: `Scene::add_back_emitters` gives each of its
    /// triangles a back-emitting twin, and each of the two is seen from its front only.
    pub fn emits_both_sides(&self) -> bool {
        self.double_sided && self.emission.max_element() > 0.0
    }

    /// Whether anything in it varies over a surface (textures or a cut-out).
    pub fn varies(&self) -> bool {
        self.base_color_texture.is_some()
            || self.emissive_texture.is_some()
            || self.alpha_cutoff.is_some()
    }
}

/// One triangle list with one material, in its node's local space.
#[derive(Clone, Debug, Default)]
pub struct Primitive {
    pub positions: Vec<Vec3>,
    pub indices: Vec<u32>,
    pub material: usize,
    /// TEXCOORD_0 and TEXCOORD_1, one per position.
    pub uv: [Option<Vec<Vec2>>; 2],
    /// COLOR_0 (linear RGBA), one per position.
    pub colors: Option<Vec<Vec4>>,
}

/// Per-triangle vertex attributes of a frame, in its triangle order and vertex order (the
/// barycentrics (b1, b2) of a hit weigh corners 1 and 2).
#[derive(Clone, Debug, Default)]
pub struct TriAttrs {
    /// TEXCOORD_0 and TEXCOORD_1 of the three corners (zero where the mesh has none).
    pub uv: Vec<[[Vec2; 3]; 2]>,
    /// COLOR_0 of the three corners (one where the mesh has none).
    pub color: Vec<[Vec4; 3]>,
}

/// A node's local transform.
#[derive(Clone, Copy, Debug)]
pub enum Local {
    Matrix(Mat4),
    Trs {
        translation: Vec3,
        rotation: Quat,
        scale: Vec3,
    },
}

impl Local {
    pub fn matrix(&self) -> Mat4 {
        match *self {
            Local::Matrix(m) => m,
            Local::Trs {
                translation,
                rotation,
                scale,
            } => Mat4::from_scale_rotation_translation(scale, rotation, translation),
        }
    }
}

/// A perspective camera as the file gives it (it looks down its node's -Z, up +Y).
#[derive(Clone, Copy, Debug)]
pub struct CameraDef {
    /// Vertical field of view in radians.
    pub yfov: f32,
}

#[derive(Clone, Debug)]
pub struct Node {
    pub name: String,
    pub local: Local,
    pub children: Vec<usize>,
    pub mesh: Option<usize>,
    pub camera: Option<CameraDef>,
    /// A KHR_lights_punctual light (index into [`Scene::lights`]).
    pub light: Option<usize>,
}

/// A scene as loaded: static description plus animation channels.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub materials: Arc<Vec<Material>>,
    /// Meshes, each a list of triangle primitives.
    pub meshes: Vec<Vec<Primitive>>,
    /// For each mesh, whether it is closed ([`culling::is_closed`]).
    pub closed: Vec<bool>,
    pub nodes: Vec<Node>,
    pub roots: Vec<usize>,
    /// The file's punctual lights, placed by the nodes that refer to them.
    pub lights: Vec<LightDef>,
    /// The node carrying the camera in use, if the file has one.
    pub camera_node: Option<usize>,
    /// A framing camera used when the file has none.
    pub default_camera: Camera,
    pub channels: Vec<Channel>,
    /// The images the materials' textures read.
    pub textures: Arc<Vec<Texture>>,
    /// Warnings raised while loading (one per kind of thing ignored).
    pub warnings: Vec<String>,
    /// A translation above every root: moves a scene that lies far from the origin back to
    /// it (zero for most scenes).
    pub shift: Vec3,
    /// The radiance from where rays meet no geometry (None: black). The loader puts the
    /// default sky here when nothing else lights the scene; `--environment` chooses.
    pub environment: Option<Arc<Environment>>,
    /// Why the file alone lights nothing (no emitter, no punctual light), when so: the
    /// loader then gave it the default sky, and this is the note saying so.
    pub unlit: Option<String>,
    /// The triangles' mean emission where a texture or a cutout makes it vary, kept between
    /// frames ([`EmissionMeans`]).
    pub emission_means: EmissionMeans,
}

/// Lattice points in all for the mean emission of the triangles whose emission varies.
pub const LATTICE_BUDGET: usize = 1 << 26;

/// The side of the lattice each of `varying` triangles' mean emission is taken on: 32 (1024
/// points) while that fits [`LATTICE_BUDGET`] (every scene up to 65,536 such triangles),
/// fewer for more, at least 8.
pub fn lattice_side(varying: usize) -> u32 {
    let n = (LATTICE_BUDGET as f64 / varying.max(1) as f64)
        .sqrt()
        .floor();
    (n as u32).clamp(8, 32)
}

/// Each triangle's mean emitted radiance where it varies over the triangle (an emissive
/// texture, an alpha MASK): an average over a lattice of points, the same at every time
/// (it depends on texture coordinates, vertex colours and materials, which do not move), so
/// it is computed once and kept while a fingerprint of those inputs is unchanged. Clones of
/// the scene share it (the fingerprint keeps a clone whose materials changed from using
/// another's means).
#[derive(Clone, Default)]
pub struct EmissionMeans(Arc<std::sync::Mutex<Option<KeptMeans>>>);

/// A fingerprint of what the means depend on, and the means.
type KeptMeans = (u64, Arc<Vec<Vec3>>);

impl std::fmt::Debug for EmissionMeans {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("EmissionMeans")
    }
}

impl EmissionMeans {
    /// The mean emission of every triangle of `frame` (computed in parallel on a miss).
    fn of(&self, frame: &Frame) -> Arc<Vec<Vec3>> {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        frame.tri_material.hash(&mut h);
        if let Some(a) = &frame.attrs {
            let floats = |v: &[f32], h: &mut std::collections::hash_map::DefaultHasher| {
                for x in v {
                    x.to_bits().hash(h);
                }
            };
            for (uv, c) in a.uv.iter().zip(&a.color) {
                floats(&[uv[0][0].x, uv[0][0].y, uv[0][1].x, uv[0][1].y], &mut h);
                floats(&[uv[0][2].x, uv[0][2].y, uv[1][0].x, uv[1][0].y], &mut h);
                floats(&[uv[1][1].x, uv[1][1].y, uv[1][2].x, uv[1][2].y], &mut h);
                for v in c {
                    floats(&v.to_array(), &mut h);
                }
            }
        }
        format!("{:?}", frame.materials).hash(&mut h);
        for t in frame.textures.iter() {
            (&t.name, t.width, t.height, t.texels.len()).hash(&mut h);
        }
        let key = h.finish();
        {
            let kept = self.0.lock().unwrap_or_else(|e| e.into_inner());
            if let Some((k, means)) = kept.as_ref() {
                if *k == key && means.len() == frame.tris.len() {
                    return means.clone();
                }
            }
        }
        // Computed without the lock held: a rayon worker that picks up another frame's
        // evaluation while this one waits for its points never waits on itself.
        use rayon::prelude::*;
        let varying = (0..frame.tris.len())
            .filter(|&t| frame.emission_varies(t))
            .count();
        let n = lattice_side(varying);
        let means: Arc<Vec<Vec3>> = Arc::new(
            (0..frame.tris.len())
                .into_par_iter()
                .map(|i| frame.mean_emission(i, n))
                .collect(),
        );
        *self.0.lock().unwrap_or_else(|e| e.into_inner()) = Some((key, means.clone()));
        means
    }
}

/// What lights a frame: emissive triangles, with a CDF for choosing one in proportion to
/// power, and punctual lights, with their own.
#[derive(Clone, Debug, Default)]
pub struct Emitters {
    /// Triangle indices into the frame.
    pub tris: Vec<u32>,
    /// Power of each emitter triangle (RGB watts): `Le * pi * area`.
    pub power: Vec<Vec3>,
    /// Cumulative luminance power, normalized to end at 1.
    pub cdf: Vec<f32>,
    /// Total RGB power of all emitter triangles.
    pub total_power: Vec3,
    /// The punctual lights that shine at this time.
    pub lights: Vec<PunctualLight>,
    /// Cumulative luminance power of the punctual lights, normalized to end at 1.
    pub light_cdf: Vec<f32>,
    /// Total RGB power of the punctual lights.
    pub light_power: Vec3,
    /// The sphere around the frame's geometry (centre, radius): where a directional light's
    /// light comes in through.
    pub sphere: (Vec3, f32),
    /// The environment, if any (see [`Scene::environment`]).
    pub environment: Option<Arc<Environment>>,
    /// The environment's RGB power into `sphere` ([`Environment::power`]).
    pub env_power: Vec3,
}

impl Emitters {
    /// Makes `tris` (with their `power`) the emitter triangles: the CDF in proportion to
    /// luminance power, the total power, and each one's index in `emitter_of_tri` (the
    /// frame's, whose entries for the triangles that were emitters are cleared first).
    fn set_triangles(&mut self, tris: Vec<u32>, power: Vec<Vec3>, emitter_of_tri: &mut [u32]) {
        for &t in &self.tris {
            emitter_of_tri[t as usize] = u32::MAX;
        }
        let mut acc = 0.0f32;
        self.cdf.clear();
        self.total_power = Vec3::ZERO;
        for (k, (&t, &p)) in tris.iter().zip(&power).enumerate() {
            emitter_of_tri[t as usize] = k as u32;
            self.total_power += p;
            acc += crate::math::luminance(p).max(1e-20);
            self.cdf.push(acc);
        }
        for c in &mut self.cdf {
            *c /= acc;
        }
        (self.tris, self.power) = (tris, power);
    }

    /// Picks an emitter by a uniform number: (index into `tris`, probability).
    pub fn pick(&self, u: f32) -> (usize, f32) {
        let i = self
            .cdf
            .partition_point(|&c| c <= u)
            .min(self.cdf.len() - 1);
        (i, self.prob(i))
    }

    /// Probability of picking emitter `i`.
    pub fn prob(&self, i: usize) -> f32 {
        let prev = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        self.cdf[i] - prev
    }

    /// Picks a punctual light by a uniform number, in proportion to power: (index into
    /// `lights`, probability).
    pub fn pick_light(&self, u: f32) -> (usize, f32) {
        let c = &self.light_cdf;
        let i = c.partition_point(|&x| x <= u).min(c.len() - 1);
        (i, c[i] - if i == 0 { 0.0 } else { c[i - 1] })
    }

    /// Whether anything lights the frame.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty() && self.lights.is_empty() && self.environment.is_none()
    }

    /// The probability that a light path starts at the environment: its share of the
    /// luminance power of everything that lights the frame (0 without one).
    pub fn environment_share(&self) -> f32 {
        if self.environment.is_none() {
            return 0.0;
        }
        let e = crate::math::luminance(self.env_power);
        let rest = crate::math::luminance(self.total_power + self.light_power);
        if self.tris.is_empty() && self.lights.is_empty() {
            1.0
        } else if e + rest > 0.0 {
            e / (e + rest)
        } else {
            0.0
        }
    }

    /// The probability that a light path starts on an emitter triangle rather than at a
    /// punctual light: their shares of the luminance power (1 without punctual lights).
    pub fn area_share(&self) -> f32 {
        if self.lights.is_empty() {
            return 1.0;
        }
        let a = crate::math::luminance(self.total_power);
        let l = crate::math::luminance(self.light_power);
        if self.tris.is_empty() || a + l <= 0.0 {
            0.0
        } else {
            a / (a + l)
        }
    }

    /// How far back along a directional light's direction a point's visibility is tested:
    /// past the sphere around the geometry from anywhere inside it.
    pub fn far(&self) -> f32 {
        4.0 * self.sphere.1.max(1e-3)
    }
}

/// The classes of [`Frame::sides`].
pub struct Sides;

impl Sides {
    /// Double-sided: seen, lit and casting shadows from both sides.
    pub const DOUBLE: u8 = 0;
    /// Single-sided on a closed mesh: invisible from behind; as an occluder seen from a light
    /// outside the solid, the same as double-sided.
    pub const SOLID: u8 = 1;
    /// Single-sided on an open mesh: invisible from behind, to shadow rays too.
    pub const OPEN: u8 = 2;
}

/// The scene evaluated at one time: everything the frame's stages need.
#[derive(Clone, Debug)]
pub struct Frame {
    pub time: f32,
    /// World-space triangles, in an order stable over time (same index, same surface).
    pub tris: Vec<[Vec3; 3]>,
    pub tri_material: Vec<u32>,
    /// Unit geometric normals (from the winding, counter-clockwise front).
    pub normals: Vec<Vec3>,
    pub areas: Vec<f32>,
    pub materials: Arc<Vec<Material>>,
    pub textures: Arc<Vec<Texture>>,
    /// Vertex attributes, where a material has a texture or a mesh has vertex colours (None:
    /// every surface is its material's factors).
    pub attrs: Option<Arc<TriAttrs>>,
    pub camera: Camera,
    pub emitters: Emitters,
    /// For each triangle, its index in `emitters.tris`, or `u32::MAX`.
    pub emitter_of_tri: Vec<u32>,
    /// The mesh instances, in triangle order: what the raster passes may leave out of a view
    /// ([`culling::CullView::runs`]).
    pub instances: Vec<culling::Instance>,
}

impl Frame {
    /// Keeps only the emitter triangles `keep` accepts (by triangle index): their CDF, total
    /// power and [`Frame::emitter_of_tri`] follow. Light paths and emitter samples are then
    /// drawn among them alone, in proportion to their power. For the back-facing twins that
    /// line a closed lamp's inside (`trace::solids`): their light reaches nothing the frame
    /// shows, and drawn with the rest they took half of a double-sided closed lamp's paths
    /// and direct-light samples. Returns how many were dropped.
    pub fn keep_emitters(&mut self, keep: impl Fn(u32) -> bool) -> usize {
        let em = &mut self.emitters;
        let before = em.tris.len();
        if em.tris.iter().all(|&t| keep(t)) {
            return 0;
        }
        let (tris, power): (Vec<u32>, Vec<Vec3>) = em
            .tris
            .iter()
            .zip(&em.power)
            .filter(|(&t, _)| keep(t))
            .map(|(&t, &p)| (t, p))
            .unzip();
        em.set_triangles(tris, power, &mut self.emitter_of_tri);
        before - em.tris.len()
    }

    /// The material's albedo factor (the mean albedo of an untextured triangle without vertex
    /// colours; [`Frame::albedo_at`] is the albedo at a point).
    pub fn albedo(&self, tri: usize) -> Vec3 {
        self.materials[self.tri_material[tri] as usize].albedo
    }
    /// The material's emission factor ([`Frame::emission_at`] is the emission at a point).
    pub fn emission(&self, tri: usize) -> Vec3 {
        self.materials[self.tri_material[tri] as usize].emission
    }

    /// A texture's value at barycentrics (b1, b2) of triangle `tri`.
    fn texture_at(&self, r: &TexRef, tri: usize, b1: f32, b2: f32) -> Vec4 {
        let Some(a) = &self.attrs else {
            return Vec4::ONE;
        };
        let uv = a.uv[tri][r.texcoord.min(1) as usize];
        let p = uv[0] * (1.0 - b1 - b2) + uv[1] * b1 + uv[2] * b2;
        match self.textures.get(r.texture) {
            Some(t) => t.sample(r.apply(p)),
            None => Vec4::ONE,
        }
    }

    fn color_at(&self, tri: usize, b1: f32, b2: f32) -> Vec4 {
        match &self.attrs {
            Some(a) => {
                let c = a.color[tri];
                c[0] * (1.0 - b1 - b2) + c[1] * b1 + c[2] * b2
            }
            None => Vec4::ONE,
        }
    }

    /// Albedo and alpha at barycentrics (b1, b2): factor x base colour texture x vertex colour.
    pub fn base_color_at(&self, tri: usize, b1: f32, b2: f32) -> Vec4 {
        let m = &self.materials[self.tri_material[tri] as usize];
        let mut c = m.albedo.extend(m.alpha);
        if self.attrs.is_none() {
            return c;
        }
        if let Some(r) = &m.base_color_texture {
            c *= self.texture_at(r, tri, b1, b2);
        }
        c * self.color_at(tri, b1, b2)
    }

    /// Albedo at barycentrics (b1, b2) of triangle `tri`.
    pub fn albedo_at(&self, tri: usize, b1: f32, b2: f32) -> Vec3 {
        self.base_color_at(tri, b1, b2).truncate()
    }

    /// Emitted radiance at barycentrics (b1, b2): factor x emissive texture (nothing where an
    /// alpha MASK cuts the surface away).
    pub fn emission_at(&self, tri: usize, b1: f32, b2: f32) -> Vec3 {
        let m = &self.materials[self.tri_material[tri] as usize];
        if m.alpha_cutoff.is_some() && m.emission.max_element() > 0.0 && self.cut_at(tri, b1, b2) {
            return Vec3::ZERO;
        }
        match &m.emissive_texture {
            Some(r) if m.emission.max_element() > 0.0 => {
                m.emission * self.texture_at(r, tri, b1, b2).truncate()
            }
            _ => m.emission,
        }
    }

    /// Whether the point at barycentrics (b1, b2) is cut away by an alpha MASK.
    pub fn cut_at(&self, tri: usize, b1: f32, b2: f32) -> bool {
        let m = &self.materials[self.tri_material[tri] as usize];
        match m.alpha_cutoff {
            Some(cut) => self.base_color_at(tri, b1, b2).w < cut,
            None => false,
        }
    }

    /// The mean emitted radiance over triangle `tri`: the factor, or with an emissive texture
    /// or an alpha MASK its mean over an `n` x `n` stratified lattice of points of the
    /// triangle (so that emitters are chosen by their power; the points sampled on them carry
    /// their own radiance); `n` from [`lattice_side`].
    pub fn mean_emission(&self, tri: usize, n: u32) -> Vec3 {
        if !self.emission_varies(tri) {
            return self.materials[self.tri_material[tri] as usize].emission;
        }
        self.lattice_mean(tri, n)
    }

    /// Whether triangle `tri`'s emission varies over it (an emissive texture or an alpha
    /// MASK on an emitting material, with texture coordinates to read them by).
    pub fn emission_varies(&self, tri: usize) -> bool {
        let m = &self.materials[self.tri_material[tri] as usize];
        (m.emissive_texture.is_some() || m.alpha_cutoff.is_some())
            && self.attrs.is_some()
            && m.emission.max_element() > 0.0
    }

    /// The mean emission over an `n` x `n` stratified lattice of points of triangle `tri`.
    pub fn lattice_mean(&self, tri: usize, n: u32) -> Vec3 {
        let mut sum = Vec3::ZERO;
        for i in 0..n {
            for j in 0..n {
                // The centre of cell (i, j) of the unit square, folded onto the triangle.
                let (u, v) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let (b1, b2) = if u + v > 1.0 {
                    (1.0 - u, 1.0 - v)
                } else {
                    (u, v)
                };
                sum += self.emission_at(tri, b1, b2);
            }
        }
        sum / (n * n) as f32
    }

    /// How each triangle is seen from behind, or None when every triangle is double-sided
    /// (see docs/math.md, "Single-sided surfaces"): [`Sides::DOUBLE`] for a double-sided
    /// material, [`Sides::SOLID`] for a single-sided one on a closed mesh, [`Sides::OPEN`]
    /// for a single-sided one elsewhere; [`Sides::SOLID`] for double-sided emitters and their
    /// back-emitting twins (`Scene::add_back_emitters`), each seen from its front only: the
    /// two lie 1e-4 of the scene apart, closer than the G-buffer's depth resolves, and the
    /// one seen from behind won the depth test on parts of a lamp's face, which then showed a
    /// back: no emission.
    pub fn sides(&self) -> Option<Vec<u8>> {
        let twins = match self.instances.iter().map(|i| i.tris.end).max() {
            Some(end) => end as usize,
            None => self.tris.len(),
        };
        let single =
            |t: usize| t >= twins || !self.materials[self.tri_material[t] as usize].double_sided;
        if !(0..self.tris.len()).any(single) {
            return None;
        }
        let mut s: Vec<u8> = (0..self.tris.len())
            .map(|t| {
                if single(t) {
                    Sides::OPEN
                } else {
                    Sides::DOUBLE
                }
            })
            .collect();
        for i in self.instances.iter().filter(|i| i.closed) {
            for t in i.tris.clone() {
                if s[t as usize] == Sides::OPEN {
                    s[t as usize] = Sides::SOLID;
                }
            }
        }
        for side in s.iter_mut().skip(twins) {
            *side = Sides::SOLID;
        }
        // And their parents likewise: from behind, the twin lies 1e-4 of the scene in front
        // of its parent, and the parent's back, which emits nothing, won the depth test on part
        // of a lamp seen from behind (a quarter of two pixels of the textured room in
        // tests/gpu/textures.rs, 1.3% of its light).
        for (t, side) in s.iter_mut().enumerate().take(twins) {
            if self.materials[self.tri_material[t] as usize].emits_both_sides() {
                *side = Sides::SOLID;
            }
        }
        Some(s)
    }

    /// Whether any triangle can be cut away (ray casting then tests every hit).
    pub fn has_cutouts(&self) -> bool {
        self.attrs.is_some() && self.materials.iter().any(|m| m.alpha_cutoff.is_some())
    }
    /// A point on a triangle from barycentrics (b1, b2).
    pub fn point(&self, tri: usize, b1: f32, b2: f32) -> Vec3 {
        let [a, b, c] = self.tris[tri];
        a * (1.0 - b1 - b2) + b * b1 + c * b2
    }
    /// Axis-aligned bounds of all triangles.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        bounds(self.tris.iter().flatten().copied())
    }

    /// The box around every triangle with a vertex in front of the plane through `p` with
    /// normal `n` (the whole triangle, so it holds every point light from `p` can reach); an
    /// empty box (lo > hi) if there is none.
    pub fn bounds_in_front(&self, p: Vec3, n: Vec3) -> (Vec3, Vec3) {
        let eps = 1e-5 * self.emitters.sphere.1;
        bounds(
            self.tris
                .iter()
                .filter(|t| t.iter().any(|&v| n.dot(v - p) > eps))
                .flatten()
                .copied(),
        )
    }
}

pub(crate) fn bounds(points: impl Iterator<Item = Vec3>) -> (Vec3, Vec3) {
    points.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
        (lo.min(p), hi.max(p))
    })
}

impl Scene {
    /// Renders from `eye` toward `target` with vertical field of view `yfov` (radians)
    /// instead of the file's camera (up is +Y, or +Z when looking straight up or down). The
    /// message says which of the three is wrong.
    pub fn set_camera(&mut self, eye: Vec3, target: Vec3, yfov: f32) -> Result<(), String> {
        let lim = MAX_COORD;
        for (what, p) in [("eye", eye), ("target", target)] {
            if !p.is_finite() || p.abs().max_element() > lim {
                return Err(format!(
                    "the {what} {p} is not a finite point within {lim:e} of the origin"
                ));
            }
        }
        let d = target - eye;
        if d.length() <= 1e-6 * eye.abs().max_element().max(1.0) {
            return Err(format!("the eye and the target are the same point {eye}"));
        }
        let (lo, hi) = camera::FOV_RANGE;
        if !(lo..=hi).contains(&yfov) {
            return Err(format!(
                "the field of view {yfov} rad ({:.1} degrees) is outside {lo}..{hi} rad",
                yfov.to_degrees()
            ));
        }
        let up = if d.normalize().y.abs() > 0.99 {
            Vec3::Z
        } else {
            Vec3::Y
        };
        let (eye, target) = (eye + self.shift, target + self.shift);
        self.default_camera = Camera::look_at(eye, target, up, yfov);
        self.camera_node = None;
        Ok(())
    }

    /// Length of the animation in seconds (0 for a still scene).
    pub fn duration(&self) -> f32 {
        self.channels
            .iter()
            .filter_map(|c| c.times.last().copied())
            .fold(0.0, f32::max)
    }

    /// Local transforms of all nodes at time `t`.
    fn locals_at(&self, t: f32) -> Vec<Mat4> {
        let mut trs: Vec<Local> = self.nodes.iter().map(|n| n.local).collect();
        for ch in &self.channels {
            if let Local::Trs {
                translation,
                rotation,
                scale,
            } = &mut trs[ch.node]
            {
                match ch.sample(t) {
                    anim::Value::Translation(v) => *translation = v,
                    anim::Value::Rotation(q) => *rotation = q,
                    anim::Value::Scale(v) => *scale = v,
                }
            }
        }
        trs.iter().map(Local::matrix).collect()
    }

    /// World matrices of all nodes at time `t` (nodes not reached from a root stay identity).
    pub fn world_matrices(&self, t: f32) -> Vec<Mat4> {
        let locals = self.locals_at(t);
        let mut world = vec![Mat4::IDENTITY; self.nodes.len()];
        let top = Mat4::from_translation(self.shift);
        let mut stack: Vec<(usize, Mat4)> = self.roots.iter().map(|&r| (r, top)).collect();
        while let Some((n, parent)) = stack.pop() {
            world[n] = parent * locals[n];
            for &c in &self.nodes[n].children {
                stack.push((c, world[n]));
            }
        }
        world
    }

    /// The camera of the file's camera node at time `t`, as its transform gives it (None
    /// without one; not checked: see [`Camera::is_valid`]).
    pub fn file_camera(&self, t: f32) -> Option<Camera> {
        let n = self.camera_node?;
        let world = self.world_matrices(t);
        Some(Camera::from_world(
            world[n],
            self.nodes[n].camera.map_or(0.7, |c| c.yfov),
        ))
    }

    /// World-space triangles and their materials in depth-first node order. A node whose
    /// world matrix mirrors (negative determinant) has its winding flipped, so that front
    /// faces stay front faces (glTF 2.0 section 3.7.4).
    #[allow(clippy::type_complexity)]
    fn triangles(
        &self,
        world: &[Mat4],
    ) -> (
        Vec<[Vec3; 3]>,
        Vec<u32>,
        Option<TriAttrs>,
        Vec<culling::Instance>,
    ) {
        let mut tris = Vec::new();
        let mut instances = Vec::new();
        let mut tri_material = Vec::new();
        let needs_attrs = self.materials.iter().any(Material::varies)
            || self.meshes.iter().flatten().any(|p| p.colors.is_some());
        let mut attrs = needs_attrs.then(TriAttrs::default);
        let mut order = Vec::new();
        let mut stack: Vec<usize> = self.roots.iter().rev().copied().collect();
        while let Some(n) = stack.pop() {
            order.push(n);
            stack.extend(self.nodes[n].children.iter().rev());
        }
        for n in order {
            let Some(mesh) = self.nodes[n].mesh else {
                continue;
            };
            let m = world[n];
            let (b, c) = if m.determinant() < 0.0 {
                (2, 1)
            } else {
                (1, 2)
            };
            let first = tris.len();
            for prim in &self.meshes[mesh] {
                let p: Vec<Vec3> = prim
                    .positions
                    .iter()
                    .map(|&p| m.transform_point3(p))
                    .collect();
                for idx in prim.indices.chunks_exact(3) {
                    let corners = [idx[0] as usize, idx[b] as usize, idx[c] as usize];
                    tris.push(corners.map(|k| p[k]));
                    tri_material.push(prim.material as u32);
                    if let Some(a) = &mut attrs {
                        let uv = |set: usize| match &prim.uv[set] {
                            Some(uv) => corners.map(|k| uv.get(k).copied().unwrap_or(Vec2::ZERO)),
                            None => [Vec2::ZERO; 3],
                        };
                        a.uv.push([uv(0), uv(1)]);
                        a.color.push(match &prim.colors {
                            Some(col) => corners.map(|k| col.get(k).copied().unwrap_or(Vec4::ONE)),
                            None => [Vec4::ONE; 3],
                        });
                    }
                }
            }
            // An affine map keeps a closed mesh closed, its winding put right where it mirrors;
            // one that flattens it (a zero scale) leaves coincident faces turned opposite ways,
            // of which the one facing the eye is drawn.
            if tris.len() > first {
                let (lo, hi) = bounds(tris[first..].iter().flatten().copied());
                instances.push(culling::Instance {
                    tris: first as u32..tris.len() as u32,
                    lo,
                    hi,
                    closed: self.closed.get(mesh).copied().unwrap_or(false),
                });
            }
        }
        self.add_back_emitters(&mut tris, &mut tri_material, attrs.as_mut());
        (tris, tri_material, attrs, instances)
    }

    /// For each triangle of a double-sided emitting material, a twin with the opposite
    /// winding 1e-4 of the scene's size behind it, so that the back emits too while every
    /// stage keeps treating emitters as one-sided (appended, so indices stay stable).
    fn add_back_emitters(
        &self,
        tris: &mut Vec<[Vec3; 3]>,
        mats: &mut Vec<u32>,
        mut attrs: Option<&mut TriAttrs>,
    ) {
        let two_sided = |m: u32| self.materials[m as usize].emits_both_sides();
        if !mats.iter().any(|&m| two_sided(m)) {
            return;
        }
        let (lo, hi) = bounds(tris.iter().flatten().copied());
        let gap = 1e-4 * (hi - lo).max_element();
        for i in 0..tris.len() {
            if two_sided(mats[i]) {
                let [a, b, c] = tris[i];
                let back = -(b - a).cross(c - a).normalize_or_zero() * gap;
                tris.push([a + back, c + back, b + back]);
                mats.push(mats[i]);
                if let Some(at) = attrs.as_deref_mut() {
                    let swap = |[x, y, z]: [Vec2; 3]| [x, z, y];
                    let [u0, u1] = at.uv[i];
                    at.uv.push([swap(u0), swap(u1)]);
                    let [x, y, z] = at.color[i];
                    at.color.push([x, z, y]);
                }
            }
        }
    }

    /// The punctual lights of the nodes under the roots, placed by their world matrices
    /// (depth-first node order). A light scaled to nothing (no direction) or without power at
    /// this time is left out. Directions are the transformed -Z axes, so a mirroring node
    /// mirrors where its lights point along with its geometry.
    fn place_lights(&self, world: &[Mat4], em: &mut Emitters) {
        if self.lights.is_empty() {
            return;
        }
        let r = em.sphere.1;
        let mut acc = 0.0f32;
        let mut stack: Vec<usize> = self.roots.iter().rev().copied().collect();
        while let Some(n) = stack.pop() {
            stack.extend(self.nodes[n].children.iter().rev());
            let Some((light, def)) = self.nodes[n]
                .light
                .and_then(|l| Some((l, self.lights.get(l)?)))
            else {
                continue;
            };
            let m = world[n];
            let position = m.transform_point3(Vec3::ZERO);
            let direction = m.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
            let power = match def.kind {
                LightKind::Directional => def.intensity * (std::f32::consts::PI * r * r),
                kind => def.intensity * kind.solid_angle(),
            };
            let lum = crate::math::luminance(power);
            let placed =
                position.is_finite() && (def.kind == LightKind::Point || direction != Vec3::ZERO);
            if !(placed && lum > 0.0 && lum.is_finite()) {
                continue;
            }
            em.lights.push(PunctualLight {
                light,
                kind: def.kind,
                position,
                direction,
                intensity: def.intensity,
                power,
            });
            em.light_power += power;
            acc += lum;
            em.light_cdf.push(acc);
        }
        for c in &mut em.light_cdf {
            *c /= acc;
        }
    }

    /// Evaluates the scene at time `t` (seconds).
    pub fn at(&self, t: f32) -> Frame {
        let world = self.world_matrices(t);
        let (tris, tri_material, attrs, instances) = self.triangles(&world);
        let mut normals = Vec::with_capacity(tris.len());
        let mut areas = Vec::with_capacity(tris.len());
        for [a, b, c] in &tris {
            let cr = (*b - *a).cross(*c - *a);
            areas.push(0.5 * cr.length());
            normals.push(cr.normalize_or_zero());
        }
        let camera = match self.camera_node {
            Some(n) => Camera::from_world(world[n], self.nodes[n].camera.map_or(0.7, |c| c.yfov)),
            None => self.default_camera,
        };
        // A camera scaled to nothing between the times the loader checked: the framing one.
        let camera = Some(camera)
            .filter(Camera::is_valid)
            .unwrap_or(self.default_camera);
        let mut frame = Frame {
            time: t,
            emitter_of_tri: vec![u32::MAX; tris.len()],
            tris,
            tri_material,
            normals,
            areas,
            materials: self.materials.clone(),
            textures: self.textures.clone(),
            attrs: attrs.map(Arc::new),
            camera,
            emitters: Emitters::default(),
            instances,
        };
        let mut emitters = Emitters::default();
        // Where emission varies over triangles (textures, cutouts) their means are kept
        // between frames; elsewhere each is its material's factor.
        let varies = frame.attrs.is_some()
            && frame.materials.iter().any(|m| {
                m.emission.max_element() > 0.0
                    && (m.emissive_texture.is_some() || m.alpha_cutoff.is_some())
            });
        let means = varies.then(|| self.emission_means.of(&frame));
        let (mut tris, mut power) = (Vec::new(), Vec::new());
        for i in 0..frame.tris.len() {
            let le = match &means {
                Some(m) => m[i],
                None => frame.materials[frame.tri_material[i] as usize].emission,
            };
            if le.max_element() > 0.0 && frame.areas[i] > 0.0 {
                tris.push(i as u32);
                power.push(le * std::f32::consts::PI * frame.areas[i]);
            }
        }
        emitters.set_triangles(tris, power, &mut frame.emitter_of_tri);
        let (lo, hi) = frame.bounds();
        emitters.sphere = if frame.tris.is_empty() {
            (Vec3::ZERO, 1.0)
        } else {
            ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-3))
        };
        self.place_lights(&world, &mut emitters);
        if let Some(env) = &self.environment {
            emitters.env_power = env.power(emitters.sphere.1);
            emitters.environment = Some(env.clone());
        }
        frame.emitters = emitters;
        frame
    }
}
