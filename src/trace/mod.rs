//! Stage 2: ray tracing on the CPU. An obvhs compressed wide BVH over the frame's triangles,
//! with closest-hit and occlusion queries; rebuilt only when the geometry moved.

pub mod edges;
pub mod solids;

use crate::scene::{Frame, Sides};
use glam::{Vec3, Vec3A};
use obvhs::{cwbvh::CwBvh, ray::Ray, ray::RayHit, triangle::Triangle, BvhBuildParams};
use std::time::Duration;

/// A closest hit: distance, triangle and barycentrics (b1, b2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub tri: u32,
    pub b1: f32,
    pub b2: f32,
}

/// A ray of a light-transport path (the path tracer's, a light path's, a compensation walk's,
/// stochastic radiosity's): from the eye or a light ([`PathRay::free`]), or leaving a surface
/// ([`Tracer::leave`]), whose next hit [`Tracer::follow`] ends if it lies in a gap thinner
/// than the tracer resolves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathRay {
    pub origin: Vec3,
    /// Unit direction.
    pub dir: Vec3,
    /// The normal of the surface it leaves (None: from no surface).
    from: Option<Vec3>,
}

impl PathRay {
    /// A ray from no surface: the eye, a punctual light, the environment.
    pub fn free(origin: Vec3, dir: Vec3) -> Self {
        PathRay {
            origin,
            dir,
            from: None,
        }
    }
}

/// Where a [`PathRay`] goes next.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Next {
    /// It hits `Hit`.
    Hit(Hit),
    /// Into a gap thinner than the tracer resolves (its hit less than [`SEAL`] of the scene's
    /// size off the plane it left): its path ends, as such a gap takes in light and gives none
    /// back.
    Sealed,
    /// Out of the scene.
    Miss,
}

/// Ray-tracing acceleration over one frame's triangles: a BVH over the triangles that have
/// not moved and a small one over those that have (an animated emitter, a moving object), so
/// that a frame in which a few triangles move rebuilds only the small one.
pub struct Tracer {
    /// The triangles that were still when it was last built, and those that moved.
    still: Part,
    moving: Part,
    /// Every triangle of the frame, by the frame's index.
    tris: Vec<Triangle>,
    /// How many times a BVH was built (for tests and run records).
    pub builds: usize,
    /// Seconds spent in the last build (0 if the last update kept the BVH).
    pub last_build_s: f64,
    /// The scene's size: its bounding box's largest side.
    size: f32,
    /// The power of two the BVH's coordinates are the frame's times ([`scale_for`]).
    k: f32,
    /// The frame, kept when an alpha MASK can cut its triangles: a hit on a cut-away point
    /// is passed through.
    cutouts: Option<Box<Frame>>,
    /// [`Frame::sides`]: which triangles are single-sided (None: none is).
    sides: Option<Vec<u8>>,
    /// The closed meshes light paths cannot be inside ([`solids::Solids`]), for the frame's
    /// camera (None: none).
    solids: Option<solids::Solids>,
}

/// Which faces of single-sided triangles a ray passes through (see docs/math.md,
/// "Single-sided surfaces").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Facing {
    /// A ray from a receiver (the eye, a shading point): their backs.
    Seen,
    /// A light path's ray: none (the caller ends the path on a back).
    Any,
    /// A ray from a light, looking for what shadows the receivers beyond: the fronts of open
    /// ones (the receivers behind them see their backs).
    Occluder,
}

/// A BVH over some of the frame's triangles.
struct Part {
    /// None when it holds no triangle.
    bvh: Option<CwBvh>,
    /// The frame's index of each of its triangles.
    ids: Vec<u32>,
}

impl Part {
    fn over(tris: &[Triangle], ids: Vec<u32>) -> Part {
        let own: Vec<Triangle> = ids.iter().map(|&i| tris[i as usize]).collect();
        Part {
            bvh: (!own.is_empty()).then(|| build(&own)),
            ids,
        }
    }
}

/// Moved triangles a frame may have, as a fraction of all, for the BVH to be split into still
/// and moving ones rather than rebuilt whole.
const MOVING_SHARE: usize = 8;

/// Barycentrics (b1, b2) of point `p` on triangle `t`, from areas (robust for any winding).
fn barycentrics(t: &Triangle, p: Vec3A) -> (f32, f32) {
    let n = (t.v1 - t.v0).cross(t.v2 - t.v0);
    let inv = 1.0 / n.length_squared();
    let b1 = (t.v2 - t.v0).cross(p - t.v0).dot(-n) * inv;
    let b2 = (t.v1 - t.v0).cross(p - t.v0).dot(n) * inv;
    (b1.clamp(0.0, 1.0), b2.clamp(0.0, 1.0))
}

/// How many units in the last place of the scene's size a ray leaving a surface starts off
/// it ([`Tracer::epsilon_at`]): 128, 1.5e-5 of the size. Of the size, not of the point's own
/// coordinates: a ray's distance to a triangle's plane, as the intersection test computes it,
/// errs by units in the last place of the triangle's extent, more for a sliver, and a triangle
/// may span the scene (`a_ray_never_hits_the_triangle_it_leaves`: some rays hit their own plane
/// at 32, none at 64). At 1e-4 of the size, as before stop 52, the offset was a fifth of a 1 mm
/// gap in a 2 m room and let half as much light again out of it (docs/math.md, "Gaps thinner
/// than the scene resolves").
pub const OFFSET_ULPS: f32 = 128.0;

/// And at least this many units in the last place of the point's largest coordinate: a point
/// interpolated on a triangle lies off its plane by a few of them, and a smaller step would be
/// lost in rounding the origin. Only beyond 16 times the scene's size from the origin is that
/// the larger, and the loader moves a scene whose centre lies more than 15 times its size
/// from the origin to it (`scene::load`), so that a scene's offsets do not depend on where it
/// sits.
pub const POINT_ULPS: f32 = 8.0;

/// The offset at `p` in a scene of `size`, with `ulps` units of the size ([`OFFSET_ULPS`]).
fn epsilon(p: Vec3, size: f32, ulps: f32) -> f32 {
    f32::EPSILON * (ulps * size).max(POINT_ULPS * p.abs().max_element())
}

/// The gap, as a share of the scene's size, narrower than which two facing surfaces are one:
/// a path ray into it is [`Next::Sealed`] ([`Tracer::follow`]).
pub const SEAL: f32 = 1e-4;

/// The power of two `k >= 1` that brings a scene of size `size` (its bounding box's largest
/// side) to at least [`BVH_SIZE`]. obvhs skips BVH nodes whose exit distance is under an
/// absolute 1e-4 (`cwbvh::node::EPSILON`): in a millimetre-sized scene that was 5% of it (a
/// 1e-3-scaled Cornell box rendered 1.1% darker in the reference), and with scenes brought
/// only to a size of 2 a ray could still pass through a surface less than 1e-4 of the BVH's
/// units ahead of it in a flat node, 5e-5 of the scene: a gap's far side, a concave corner
/// (`a_gap_thinner_than_the_seal_seals_at_any_scale_and_angle`). Multiplying by a power of
/// two is exact, so a scene modelled at any scale traces as its unit-sized twin does.
fn scale_for(size: f32) -> f32 {
    if !(size > 0.0 && size < BVH_SIZE) {
        return 1.0;
    }
    2f32.powi((BVH_SIZE / size).log2().ceil() as i32)
        .min(2f32.powi(100))
}

/// The size the BVH's coordinates bring a scene to at least ([`scale_for`]): 2^14, so that
/// obvhs's absolute 1e-4 is 6e-9 of it, far under the rays' offset (1.5e-5 of it).
const BVH_SIZE: f32 = 16384.0;

fn to_obvhs(frame: &Frame, k: f32) -> Vec<Triangle> {
    frame.tris.iter().map(|t| triangle(t, k)).collect()
}

fn triangle(&[a, b, c]: &[Vec3; 3], k: f32) -> Triangle {
    Triangle {
        v0: (a * k).into(),
        v1: (b * k).into(),
        v2: (c * k).into(),
    }
}

/// obvhs's medium build, but with PLOC's full search distance from the first merges up
/// (`search_depth_threshold` 0; medium merges only Morton-order neighbours in its first 3
/// passes). On a regularly tessellated mesh, where neighbouring merges cost the same, those
/// passes made a tree whose shadow rays cost 10-30 times as much: the importance of 1024 VPLs
/// over 256 camera points on `benches/big_mesh.py`'s 187k-triangle court took 1.40 s instead of
/// 0.08 s (4.5 s instead of 0.16 s at 1.04M triangles, 0.06 s instead of 0.022 s on the
/// atrium; one session at load average 9), for a build 15-30% longer. The same triangles are
/// hit; only the tree differs (docs/design.md, "Big meshes").
const BVH_PARAMS: BvhBuildParams = BvhBuildParams {
    search_depth_threshold: 0,
    ..BvhBuildParams::medium_build()
};

fn build(tris: &[Triangle]) -> CwBvh {
    obvhs::cwbvh::builder::build_cwbvh_from_tris(tris, BVH_PARAMS, &mut Duration::default())
}

impl Tracer {
    pub fn new(frame: &Frame) -> Self {
        let start = std::time::Instant::now();
        let (lo, hi) = frame.bounds();
        let size = (hi - lo).max_element();
        let k = scale_for(size);
        let tris = to_obvhs(frame, k);
        let still = Part::over(&tris, (0..tris.len() as u32).collect());
        Tracer {
            still,
            moving: Part::over(&[], Vec::new()),
            tris,
            builds: 1,
            last_build_s: start.elapsed().as_secs_f64(),
            size: if size > 0.0 { size } else { 1e-3 },
            k,
            cutouts: frame.has_cutouts().then(|| Box::new(frame.clone())),
            sides: frame.sides(),
            solids: solids::Solids::of(frame),
        }
    }

    /// A tracer over `frame` that treats every triangle as double-sided.
    pub fn two_sided(frame: &Frame) -> Self {
        let mut t = Tracer::new(frame);
        t.sides = None;
        t
    }

    /// Whether any triangle is single-sided.
    pub fn has_single_sided(&self) -> bool {
        self.sides.is_some()
    }

    /// Distance along `r` to the `id`-th triangle of `part`'s BVH, or infinity (a miss, or a
    /// point an alpha MASK cuts away).
    fn hit_distance(&self, part: &Part, r: &Ray, id: usize, facing: Facing) -> f32 {
        let k =
            part.ids[part.bvh.as_ref().expect("traversed").primitive_indices[id] as usize] as usize;
        if let Some(s) = &self.sides {
            let side = s[k];
            if side != Sides::DOUBLE && facing != Facing::Any {
                let t = &self.tris[k];
                let cos = (t.v1 - t.v0).cross(t.v2 - t.v0).dot(r.direction);
                let passes = match facing {
                    Facing::Seen => cos > 0.0,
                    _ => side == Sides::OPEN && cos < 0.0,
                };
                if passes {
                    return f32::INFINITY;
                }
            }
        }
        let t = self.tris[k].intersect(r);
        if let Some(f) = &self.cutouts {
            if t < f32::INFINITY {
                let p = r.origin + r.direction * t;
                let (b1, b2) = barycentrics(&self.tris[k], p);
                if f.cut_at(k, b1, b2) {
                    return f32::INFINITY;
                }
            }
        }
        t
    }

    /// Brings the BVH to `frame`'s geometry; rebuilds only if a vertex moved, and then, when
    /// few triangles moved, only the BVH of the moving ones (the first time some move, the
    /// still ones' too, without them). Returns whether it rebuilt.
    pub fn update(&mut self, frame: &Frame) -> bool {
        let start = std::time::Instant::now();
        // Which solids hold the camera changes as it moves.
        self.solids = solids::Solids::of(frame);
        if self.tris.len() != frame.tris.len() {
            return self.rebuild(frame);
        }
        let moved: Vec<u32> = (0..frame.tris.len() as u32)
            .filter(|&i| {
                let (t, f) = (&self.tris[i as usize], &frame.tris[i as usize]);
                let k = self.k;
                Vec3::from(t.v0) != f[0] * k
                    || Vec3::from(t.v1) != f[1] * k
                    || Vec3::from(t.v2) != f[2] * k
            })
            .collect();
        if moved.is_empty() {
            self.last_build_s = 0.0;
            return false;
        }
        let mut ids = self.moving.ids.clone();
        ids.extend(&moved);
        ids.sort_unstable();
        ids.dedup();
        if ids.len() * MOVING_SHARE > self.tris.len() {
            return self.rebuild(frame);
        }
        for &i in &moved {
            self.tris[i as usize] = triangle(&frame.tris[i as usize], self.k);
        }
        if ids.len() != self.moving.ids.len() {
            let mut is_moving = vec![false; self.tris.len()];
            for &i in &ids {
                is_moving[i as usize] = true;
            }
            let still = (0..self.tris.len() as u32).filter(|&i| !is_moving[i as usize]);
            self.still = Part::over(&self.tris, still.collect());
            self.builds += 1;
        }
        self.moving = Part::over(&self.tris, ids);
        self.builds += 1;
        if self.cutouts.is_some() {
            self.cutouts = Some(Box::new(frame.clone()));
        }
        self.last_build_s = start.elapsed().as_secs_f64();
        true
    }

    /// Rebuilds everything for `frame`, counting the builds so far.
    fn rebuild(&mut self, frame: &Frame) -> bool {
        let builds = self.builds;
        *self = Tracer::new(frame);
        self.builds = builds + 1;
        true
    }

    /// How many of the frame's triangles the small BVH of moving ones holds.
    pub fn moving_triangles(&self) -> usize {
        self.moving.ids.len()
    }

    /// The scene's size: its bounding box's largest side (when it was last built).
    pub fn size(&self) -> f32 {
        self.size
    }

    /// How far a ray leaving a surface at `p` starts off it ([`Tracer::offset`]):
    /// [`OFFSET_ULPS`] units in the last place of the scene's size, or [`POINT_ULPS`] of `p`'s
    /// largest coordinate if that is larger.
    pub fn epsilon_at(&self, p: Vec3) -> f32 {
        epsilon(p, self.size, OFFSET_ULPS)
    }

    /// Whether a ray that left a surface with normal `n` along `dir` (unit) and hit the next
    /// one `t` away got into a gap narrower than the tracer resolves: its hit lies less than
    /// [`SEAL`] of the scene's size off the plane it left. A light path (or a camera path) ends there: such
    /// a gap takes in light and gives none back (docs/math.md, "Gaps thinner than the scene
    /// resolves").
    fn seals(&self, n: Vec3, dir: Vec3, t: f32) -> bool {
        t * n.dot(dir).abs() < SEAL * self.size
    }

    /// The ray that leaves the surface at `p` (normal `n`, either side) along `dir` (unit):
    /// from [`Tracer::offset`] off it, to be followed by [`Tracer::follow`] or
    /// [`Tracer::follow_light`], which end it in a gap thinner than the tracer resolves.
    pub fn leave(&self, p: Vec3, n: Vec3, dir: Vec3) -> PathRay {
        PathRay {
            origin: self.offset(p, n, dir),
            dir,
            from: Some(n),
        }
    }

    /// Where `ray` goes within `tmax`, as a receiver sees ([`Tracer::intersect`]): its
    /// closest hit, sealed in a gap thinner than the tracer resolves, or a miss.
    pub fn follow(&self, ray: &PathRay, tmax: f32) -> Next {
        self.next(ray, self.intersect(ray.origin, ray.dir, tmax))
    }

    /// [`Tracer::follow`] for a light path's ray ([`Tracer::intersect_light`]).
    pub fn follow_light(&self, ray: &PathRay, tmax: f32) -> Next {
        self.next(ray, self.intersect_light(ray.origin, ray.dir, tmax))
    }

    fn next(&self, ray: &PathRay, hit: Option<Hit>) -> Next {
        match hit {
            None => Next::Miss,
            Some(h) if ray.from.is_some_and(|n| self.seals(n, ray.dir, h.t)) => Next::Sealed,
            Some(h) => Next::Hit(h),
        }
    }

    /// Closest hit along `dir` (unit) from `origin`, within `tmax`, as a receiver there sees
    /// it: through the backs of single-sided triangles.
    pub fn intersect(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        self.intersect_facing(origin, dir, tmax, Facing::Seen)
    }

    /// Closest hit of a light path's ray, whichever side: a light path ends where it strikes
    /// the back of a single-sided triangle ([`Tracer::single_sided`]).
    pub fn intersect_light(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        self.intersect_facing(origin, dir, tmax, Facing::Any)
    }

    /// Closest occluder along a ray from a light (a VPL): what hides the receivers beyond it
    /// from the light, passing through open single-sided triangles that face the light.
    pub fn intersect_occluder(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        self.intersect_facing(origin, dir, tmax, Facing::Occluder)
    }

    /// Whether triangle `tri` is single-sided (invisible from behind).
    pub fn single_sided(&self, tri: u32) -> bool {
        self.sides
            .as_ref()
            .is_some_and(|s| s[tri as usize] != Sides::DOUBLE)
    }

    /// Whether a light path's ray along `dir` that strikes triangle `tri` comes from inside
    /// a solid the camera is outside of ([`solids::Solids`]): nothing the frame shows sees it.
    pub fn struck_inside_solid(&self, tri: u32, ng: Vec3, dir: Vec3) -> bool {
        self.solids
            .as_ref()
            .is_some_and(|s| s.struck_from_inside(tri, ng, dir))
    }

    /// Whether emitting triangle `tri` shines into a solid the camera is outside of.
    pub fn emits_inside_solid(&self, tri: u32) -> bool {
        self.solids.as_ref().is_some_and(|s| s.emits_inside(tri))
    }

    /// Leaves out of `frame`'s emitters those that shine into a solid the camera is outside
    /// of (a closed lamp's back-emitting twins), so that light paths and emitter samples start
    /// only where their light gets out ([`Frame::keep_emitters`]); how many it left out.
    pub fn keep_lit_emitters(&self, frame: &mut Frame) -> usize {
        frame.keep_emitters(|tri| !self.emits_inside_solid(tri))
    }

    fn intersect_facing(&self, origin: Vec3, dir: Vec3, tmax: f32, facing: Facing) -> Option<Hit> {
        // In the BVH's coordinates (the frame's times k, exactly).
        let origin = origin * self.k;
        let mut ray = ray(origin, dir, tmax * self.k);
        let mut best = None;
        for part in [&self.still, &self.moving] {
            let Some(bvh) = &part.bvh else { continue };
            let mut hit = RayHit::none();
            if bvh.ray_traverse(ray, &mut hit, |r, id| {
                self.hit_distance(part, r, id, facing)
            }) {
                ray.tmax = hit.t;
                best = Some((
                    hit.t,
                    part.ids[bvh.primitive_indices[hit.primitive_id as usize] as usize],
                ));
            }
        }
        let (t, tri) = best?;
        let p: Vec3A = Vec3A::from(origin) + Vec3A::from(dir) * t;
        let (b1, b2) = barycentrics(&self.tris[tri as usize], p);
        Some(Hit {
            t: t / self.k,
            tri,
            b1,
            b2,
        })
    }

    /// Whether anything lies on the segment from `a` to `b` (end points excluded by offsets
    /// along the normals `na`, `nb` toward each other), as a receiver at `a` sees it: the
    /// backs of single-sided triangles let it through.
    pub fn occluded(&self, a: Vec3, na: Vec3, b: Vec3, nb: Vec3) -> bool {
        // In the BVH's coordinates (the frame's times k, exactly).
        let (ea, eb) = (self.epsilon_at(a) * self.k, self.epsilon_at(b) * self.k);
        let (a, b) = (a * self.k, b * self.k);
        let d = b - a;
        let a = a + na * ea * na.dot(d).signum();
        let b = b - nb * eb * nb.dot(d).signum();
        let d = b - a;
        let len = d.length();
        if len <= ea + eb {
            return false;
        }
        let ray = ray(a, d / len, len * (1.0 - 1e-4));
        [&self.still, &self.moving].into_iter().any(|part| {
            part.bvh.as_ref().is_some_and(|bvh| {
                !bvh.ray_traverse_miss(ray, |r, id| self.hit_distance(part, r, id, Facing::Seen))
            })
        })
    }

    /// Offsets a surface point off its triangle, to the side `dir` leaves from.
    /// By [`Tracer::epsilon_at`] `p`, along `n` (unit).
    pub fn offset(&self, p: Vec3, n: Vec3, dir: Vec3) -> Vec3 {
        p + n * (self.epsilon_at(p) * n.dot(dir).signum())
    }
}

/// An obvhs ray from `origin` along `dir` (unit) up to `tmax`, with any `-0.0` component of
/// `dir` made `+0.0`: obvhs 0.4's traversal takes a ray's octant from `d < 0.0` (false for
/// `-0.0`) and its inverse direction from the sign bit (`-1 / EPSILON`), so the two disagree
/// and a ray such as `-Vec3::Y`, `(-0, -1, -0)`, missed everything.
fn ray(origin: Vec3, dir: Vec3, tmax: f32) -> Ray {
    Ray::new(origin.into(), (dir + Vec3::ZERO).into(), 0.0, tmax)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    /// A ray's direction may carry `-0.0` components (a negated axis-aligned normal): it hits
    /// and is occluded as the same ray with `+0.0` ones. Before, `-Vec3::Y` from inside the
    /// Cornell box hit nothing at all.
    #[test]
    fn negative_zero_components_do_not_lose_the_ray() {
        let scene = builtin::load("cornell").unwrap().unwrap();
        let f = scene.at(0.0);
        let tr = Tracer::new(&f);
        let o = Vec3::new(0.013, 0.5, 0.198);
        for (axis, plain) in [
            (Vec3::X, Vec3::NEG_X),
            (Vec3::Y, Vec3::NEG_Y),
            (Vec3::Z, Vec3::NEG_Z),
        ] {
            let negated = -axis;
            assert!(negated
                .to_array()
                .iter()
                .any(|c| *c == 0.0 && c.is_sign_negative()));
            let a = tr.intersect(o, plain, f32::INFINITY).map(|h| (h.t, h.tri));
            let b = tr
                .intersect(o, negated, f32::INFINITY)
                .map(|h| (h.t, h.tri));
            assert!(a.is_some(), "{plain} from {o} hits the box");
            assert_eq!(a, b, "{negated} from {o}");
            let far = o + plain * 10.0;
            assert!(tr.occluded(o, Vec3::ZERO, far, Vec3::ZERO), "{plain}");
            assert!(tr.occluded(o, -axis, far, Vec3::ZERO), "{negated}");
        }
    }

    /// The Cornell box's frame with its triangles replaced by `tris`, every one double-sided
    /// and of one white material, in no closed mesh.
    fn frame_of(tris: Vec<[Vec3; 3]>) -> Frame {
        let scene = builtin::load("cornell").unwrap().unwrap();
        let mut f = scene.at(0.0);
        let mut materials = (*f.materials).clone();
        materials.truncate(1);
        materials[0].double_sided = true;
        f.materials = std::sync::Arc::new(materials);
        f.normals = tris
            .iter()
            .map(|[a, b, c]| (*b - *a).cross(*c - *a).normalize())
            .collect();
        f.areas = tris
            .iter()
            .map(|[a, b, c]| 0.5 * (*b - *a).cross(*c - *a).length())
            .collect();
        f.tri_material = vec![0; tris.len()];
        f.emitter_of_tri = vec![u32::MAX; tris.len()];
        f.instances.clear();
        f.attrs = None;
        f.tris = tris;
        f
    }

    /// How many rays leaving points of a triangle, offset by `ulps` units of the scene's size,
    /// hit it or its coplanar neighbour: `n` rays for each of 24 quads at each of 4 scales. The
    /// points come from rays that hit the triangle (as a path's vertices do), and the rays
    /// leave them on either side, cosine distributed or toward grazing (the cosine down to
    /// 1e-4).
    fn self_hits(ulps: f32, n: usize) -> usize {
        use crate::math::{cosine_hemisphere, rng};
        use rand::Rng;
        let mut r = rng(&[52, 0x0ff5]);
        let mut count = 0;
        for scale in [1e-3f32, 1.0, 7.3, 1e3] {
            for shape in 0..24 {
                // A quad split on its diagonal (two coplanar triangles), of random corners in
                // the box [-scale, scale]^3: large or a sliver, near the middle or a corner.
                let c = |r: &mut rand_pcg::Pcg32| {
                    Vec3::new(r.random(), r.random(), r.random()) * 2.0 - 1.0
                };
                let (a, b, d) = (c(&mut r), c(&mut r), c(&mut r));
                let (a, b, d) = match shape % 3 {
                    0 => (a, b, d),
                    1 => (a, b, a + (b - a) * 0.5 + (d - a) * 0.01),
                    _ => (a * 0.05 + Vec3::splat(0.9), b * 0.05 + Vec3::splat(0.9), d),
                };
                let (a, b, d) = (a * scale, b * scale, d * scale);
                let e = b + d - a;
                let f = frame_of(vec![[a, b, d], [b, e, d]]);
                let mut tr = Tracer::new(&f);
                // The scene is the box, whatever the quad's own extent.
                tr.size = 2.0 * scale;
                let ng = f.normals[0];
                for k in 0..n {
                    let side = if k % 2 == 0 { ng } else { -ng };
                    let bc =
                        crate::math::triangle_barycentrics(glam::Vec2::new(r.random(), r.random()));
                    let target = f.point(0, bc.x, bc.y);
                    let from = target + side * (3.0 * scale) + (c(&mut r) * scale);
                    let to = (target - from).normalize();
                    let Some(h) = tr.intersect(from, to, f32::INFINITY) else {
                        continue;
                    };
                    let p = f.point(h.tri as usize, h.b1, h.b2);
                    let cos = if k % 4 < 2 {
                        r.random::<f32>()
                    } else {
                        10f32.powf(-4.0 * r.random::<f32>())
                    };
                    let u = glam::Vec2::new(1.0 - cos * cos, r.random());
                    let w = cosine_hemisphere(side, u);
                    let o = p + side * epsilon(p, tr.size, ulps);
                    if tr.intersect(o, w, f32::INFINITY).is_some() {
                        count += 1;
                    }
                }
            }
        }
        count
    }

    /// A ray that leaves a triangle's point (a path's vertex) by [`Tracer::offset`] hits
    /// neither that triangle nor the one it shares an edge and a plane with, at any scale,
    /// shape or angle: 0 of 192000 rays, half of them at cosines log-uniform from 1e-4 to 1. By
    /// half the offset none does either; by a quarter, 8 do, so the sweep can tell.
    #[test]
    fn a_ray_never_hits_the_triangle_it_leaves() {
        let n = 2000;
        let quarter = self_hits(OFFSET_ULPS / 4.0, n);
        println!(
            "a quarter of the offset: {quarter} of {} rays hit their plane",
            96 * n
        );
        assert!(quarter > 0, "the sweep finds no self-hit even at a quarter");
        assert_eq!(self_hits(OFFSET_ULPS / 2.0, n), 0);
        assert_eq!(self_hits(OFFSET_ULPS, n), 0);
        // And Tracer::offset is that offset.
        let f = frame_of(vec![[Vec3::ZERO, Vec3::X, Vec3::Y]]);
        let tr = Tracer::new(&f);
        let p = Vec3::new(0.3, 0.2, 0.0);
        assert_eq!(
            tr.offset(p, Vec3::Z, -Vec3::Z),
            p - Vec3::Z * (OFFSET_ULPS * f32::EPSILON * tr.size())
        );
    }

    /// Two facing plates `gap` apart in a scene `scale` across: a ray that leaves the lower
    /// one is sealed when the gap is under 1e-4 of the scene's size ([`SEAL`]) and not when
    /// it is over, whatever the scale and the ray's angle; and it hits the upper plate either
    /// way (the offset, 1.5e-5 of the size, stays under the gap).
    #[test]
    fn a_gap_thinner_than_the_seal_seals_at_any_scale_and_angle() {
        use crate::math::{cosine_hemisphere, rng};
        use rand::Rng;
        let mut r = rng(&[52, 0x5ea1]);
        for scale in [1e-3f32, 1.0, 1e3] {
            for (share, sealed) in [(0.2f32, true), (0.8, true), (1.25, false), (5.0, false)] {
                let gap = share * SEAL * 2.0 * scale;
                let (lo, hi) = (-scale, scale);
                let plate = |y: f32, up: bool| {
                    let (a, b, c, d) = (
                        Vec3::new(lo, y, lo),
                        Vec3::new(hi, y, lo),
                        Vec3::new(hi, y, hi),
                        Vec3::new(lo, y, hi),
                    );
                    if up {
                        [[a, d, c], [a, c, b]]
                    } else {
                        [[a, b, c], [a, c, d]]
                    }
                };
                let mut tris = plate(0.0, true).to_vec();
                tris.extend(plate(gap, false));
                let f = frame_of(tris);
                let tr = Tracer::new(&f);
                assert!((tr.size() - 2.0 * scale).abs() <= 1e-6 * scale);
                for _ in 0..200 {
                    let x =
                        Vec3::new(r.random::<f32>() - 0.5, 0.0, r.random::<f32>() - 0.5) * scale;
                    let w = cosine_hemisphere(
                        Vec3::Y,
                        glam::Vec2::new(0.9 * r.random::<f32>(), r.random()),
                    );
                    let ray = tr.leave(x, Vec3::Y, w);
                    let h = tr
                        .intersect_light(ray.origin, w, f32::INFINITY)
                        .expect("the upper plate");
                    assert!(h.tri >= 2, "scale {scale}, gap {gap}: hit its own plate");
                    let next = tr.follow_light(&ray, f32::INFINITY);
                    if sealed {
                        assert_eq!(
                            next,
                            Next::Sealed,
                            "scale {scale}, gap {share} seals, along {w}"
                        );
                    } else {
                        assert_eq!(
                            next,
                            Next::Hit(h),
                            "scale {scale}, gap {share} seals, along {w}"
                        );
                    }
                    // From no surface, nothing seals.
                    let free = PathRay::free(ray.origin, w);
                    assert_eq!(tr.follow(&free, f32::INFINITY), Next::Hit(h));
                }
            }
        }
    }

    #[test]
    fn hits_the_back_wall_and_barycentrics_reconstruct_the_point() {
        let scene = builtin::load("cornell").unwrap().unwrap();
        let f = scene.at(0.0);
        let tr = Tracer::new(&f);
        // From the camera, above the tall box: the back wall at z = -1.
        let h = tr
            .intersect(Vec3::new(0.1, 0.5, 3.9), Vec3::NEG_Z, f32::INFINITY)
            .unwrap();
        assert!((h.t - 4.9).abs() < 1e-4, "{}", h.t);
        let p = f.point(h.tri as usize, h.b1, h.b2);
        assert!((p - Vec3::new(0.1, 0.5, -1.0)).length() < 1e-4, "{p}");
        // Straight down the axis: the tall box's front face, nearer than the back wall.
        let h = tr
            .intersect(Vec3::new(0.0, 0.0, 3.9), Vec3::NEG_Z, f32::INFINITY)
            .unwrap();
        assert!(h.t < 4.0, "{}", h.t);
        assert!(f.normals[h.tri as usize].z > 0.9, "faces the camera");
        // Upward from the floor centre: the light's front face at y = 0.99.
        let h = tr
            .intersect(Vec3::new(0.0, -0.99, 0.0), Vec3::Y, f32::INFINITY)
            .unwrap();
        assert!((h.t - 1.98).abs() < 1e-4, "{}", h.t);
        assert!(f.emission(h.tri as usize).x > 18.0);
        // Occlusion: the floor point under the small box is shadowed from the light centre.
        let under = Vec3::new(0.335, -1.0, 0.38);
        assert!(tr.occluded(under, Vec3::Y, Vec3::new(0.0, 0.99, 0.01), Vec3::NEG_Y));
        let open = Vec3::new(0.0, -1.0, 0.9);
        assert!(!tr.occluded(open, Vec3::Y, Vec3::new(0.0, 0.99, 0.01), Vec3::NEG_Y));
    }

    #[test]
    fn a_moving_light_rebuilds_only_its_own_bvh_and_rays_agree_with_a_fresh_one() {
        use crate::math::rng;
        use rand::Rng;
        // cornell-light: its emitter quad (2 of the box's triangles) slides.
        let scene = builtin::load("cornell-light").unwrap().unwrap();
        let mut tr = Tracer::new(&scene.at(0.0));
        assert!(tr.update(&scene.at(0.25)));
        assert_eq!(
            (tr.builds, tr.moving_triangles()),
            (3, 2),
            "still and moving built"
        );
        let f = scene.at(0.5);
        assert!(tr.update(&f));
        assert_eq!(tr.builds, 4, "only the moving triangles' BVH is rebuilt");
        let fresh = Tracer::new(&f);
        let mut r = rng(&[5, 6]);
        let (mut hits, mut light_hits, mut blocked) = (0, 0, 0);
        for _ in 0..20_000 {
            let o = Vec3::new(r.random(), r.random(), r.random()) * 1.9 - 0.95;
            let n = if r.random::<bool>() {
                Vec3::Y
            } else {
                -Vec3::Y
            };
            let d = crate::math::cosine_hemisphere(n, glam::Vec2::new(r.random(), r.random()));
            let (a, b) = (tr.intersect(o, d, 10.0), fresh.intersect(o, d, 10.0));
            assert_eq!(a.map(|h| h.tri), b.map(|h| h.tri), "from {o} along {d}");
            if let (Some(a), Some(b)) = (a, b) {
                assert!((a.t - b.t).abs() < 1e-5 && (a.b1 - b.b1).abs() < 1e-4);
                hits += 1;
                light_hits += (f.emission(a.tri as usize).max_element() > 0.0) as usize;
            }
            let e = o + d * 1.5;
            let occ = tr.occluded(o, d, e, -d);
            assert_eq!(occ, fresh.occluded(o, d, e, -d), "segment {o} to {e}");
            blocked += occ as usize;
        }
        // The rays must reach both BVHs for this to test anything.
        assert!(
            hits > 15_000 && light_hits > 20 && blocked > 1000,
            "{hits} {light_hits} {blocked}"
        );
    }

    /// Triangle tests per shadow ray in a box of regularly tessellated walls (a grid of `n` x
    /// `n` cells a face), between random points on its floor and its other faces, with a BVH
    /// built with `params`.
    fn tests_per_shadow_ray(n: usize, params: BvhBuildParams) -> f64 {
        use crate::math::rng;
        use rand::Rng;
        let mut tris = Vec::new();
        let corner = |f: usize, u: f32, v: f32| -> Vec3 {
            let (a, b) = (u * 2.0 - 1.0, v * 2.0 - 1.0);
            [
                Vec3::new(a, -1.0, b),
                Vec3::new(a, 1.0, b),
                Vec3::new(a, b, -1.0),
                Vec3::new(-1.0, a, b),
                Vec3::new(1.0, a, b),
            ][f]
        };
        for f in 0..5 {
            for i in 0..n {
                for j in 0..n {
                    let (u0, v0) = (i as f32 / n as f32, j as f32 / n as f32);
                    let (u1, v1) = (u0 + 1.0 / n as f32, v0 + 1.0 / n as f32);
                    let q = [
                        corner(f, u0, v0),
                        corner(f, u1, v0),
                        corner(f, u1, v1),
                        corner(f, u0, v1),
                    ];
                    tris.push(triangle(&[q[0], q[1], q[2]], 1.0));
                    tris.push(triangle(&[q[0], q[2], q[3]], 1.0));
                }
            }
        }
        let bvh =
            obvhs::cwbvh::builder::build_cwbvh_from_tris(&tris, params, &mut Duration::default());
        let mut r = rng(&[23, 5]);
        let (rays, mut tests) = (2000, 0u64);
        for _ in 0..rays {
            let a = corner(0, r.random(), r.random()) + Vec3::Y * 1e-3;
            let b = corner(r.random_range(1..5), r.random(), r.random()) * 0.999;
            let d = b - a;
            let ray = Ray::new(a.into(), d.normalize().into(), 0.0, d.length());
            bvh.ray_traverse_miss(ray, |r, id| {
                tests += 1;
                tris[bvh.primitive_indices[id] as usize].intersect(r)
            });
        }
        tests as f64 / rays as f64
    }

    /// obvhs's medium build made a poor tree of a regular tessellation (its first merges,
    /// by Morton-order neighbour only, tie everywhere): shadow rays in the big-mesh bench
    /// cost 10-30 times as much. [`BVH_PARAMS`] searches from the first merge.
    #[test]
    fn a_regular_tessellation_gets_a_tree_shadow_rays_cross_cheaply() {
        let ours = tests_per_shadow_ray(100, BVH_PARAMS);
        let medium = tests_per_shadow_ray(100, BvhBuildParams::medium_build());
        eprintln!("triangle tests per shadow ray: {ours:.1}, medium build {medium:.1}");
        // Measured: 0.0 (no ray meets a leaf box it does not cross), medium build 14.5.
        assert!(ours < 1.0, "{ours} (medium build: {medium})");
    }

    #[test]
    fn rebuilds_only_when_geometry_moves() {
        let still = builtin::load("cornell-orbit").unwrap().unwrap();
        let mut tr = Tracer::new(&still.at(0.0));
        assert!(
            !tr.update(&still.at(0.5)),
            "camera motion must not rebuild the BVH"
        );
        assert_eq!(tr.builds, 1);
        let moving = builtin::load("cornell-box").unwrap().unwrap();
        let mut tr = Tracer::new(&moving.at(0.0));
        assert!(tr.update(&moving.at(0.5)));
        assert!(!tr.update(&moving.at(0.5)));
        assert_eq!(tr.builds, 2);
    }
}
