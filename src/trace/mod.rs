//! Stage 2: ray tracing on the CPU. An obvhs compressed wide BVH over the frame's triangles,
//! with closest-hit and occlusion queries; rebuilt only when the geometry moved.

pub mod edges;

use crate::scene::Frame;
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

/// Ray-tracing acceleration over one frame's triangles.
pub struct Tracer {
    bvh: CwBvh,
    tris: Vec<Triangle>,
    /// How many times the BVH was built (for tests and run records).
    pub builds: usize,
    /// Seconds spent in the last build (0 if the last update kept the BVH).
    pub last_build_s: f64,
    /// Scale of the scene, for ray offsets.
    eps: f32,
    /// The frame, kept when an alpha MASK can cut its triangles: a hit on a cut-away point
    /// is passed through.
    cutouts: Option<Box<Frame>>,
}

/// Barycentrics (b1, b2) of point `p` on triangle `t`, from areas (robust for any winding).
fn barycentrics(t: &Triangle, p: Vec3A) -> (f32, f32) {
    let n = (t.v1 - t.v0).cross(t.v2 - t.v0);
    let inv = 1.0 / n.length_squared();
    let b1 = (t.v2 - t.v0).cross(p - t.v0).dot(-n) * inv;
    let b2 = (t.v1 - t.v0).cross(p - t.v0).dot(n) * inv;
    (b1.clamp(0.0, 1.0), b2.clamp(0.0, 1.0))
}

fn to_obvhs(frame: &Frame) -> Vec<Triangle> {
    frame
        .tris
        .iter()
        .map(|[a, b, c]| Triangle {
            v0: (*a).into(),
            v1: (*b).into(),
            v2: (*c).into(),
        })
        .collect()
}

fn build(tris: &[Triangle]) -> CwBvh {
    obvhs::cwbvh::builder::build_cwbvh_from_tris(
        tris,
        BvhBuildParams::medium_build(),
        &mut Duration::default(),
    )
}

impl Tracer {
    pub fn new(frame: &Frame) -> Self {
        let start = std::time::Instant::now();
        let tris = to_obvhs(frame);
        let bvh = build(&tris);
        let (lo, hi) = frame.bounds();
        Tracer {
            bvh,
            tris,
            builds: 1,
            last_build_s: start.elapsed().as_secs_f64(),
            eps: 1e-4 * (hi - lo).max_element().max(1e-3),
            cutouts: frame.has_cutouts().then(|| Box::new(frame.clone())),
        }
    }

    /// Distance to triangle `id` of the BVH along `r`, or infinity (a miss, or a point an
    /// alpha MASK cuts away).
    fn hit_distance(&self, r: &Ray, id: usize) -> f32 {
        let k = self.bvh.primitive_indices[id] as usize;
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

    /// Brings the BVH to `frame`'s geometry; rebuilds only if a vertex moved. Returns whether
    /// it rebuilt.
    pub fn update(&mut self, frame: &Frame) -> bool {
        let same = self.tris.len() == frame.tris.len()
            && self.tris.iter().zip(&frame.tris).all(|(t, f)| {
                Vec3::from(t.v0) == f[0] && Vec3::from(t.v1) == f[1] && Vec3::from(t.v2) == f[2]
            });
        if same {
            self.last_build_s = 0.0;
            return false;
        }
        let builds = self.builds;
        *self = Tracer::new(frame);
        self.builds = builds + 1;
        true
    }

    /// The offset used to move ray origins off surfaces.
    pub fn epsilon(&self) -> f32 {
        self.eps
    }

    /// Closest hit along `dir` (unit) from `origin`, within `tmax`.
    pub fn intersect(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        let ray = Ray::new(origin.into(), dir.into(), 0.0, tmax);
        let mut hit = RayHit::none();
        if self
            .bvh
            .ray_traverse(ray, &mut hit, |r, id| self.hit_distance(r, id))
        {
            let tri = self.bvh.primitive_indices[hit.primitive_id as usize];
            let p: Vec3A = Vec3A::from(origin) + Vec3A::from(dir) * hit.t;
            let (b1, b2) = barycentrics(&self.tris[tri as usize], p);
            Some(Hit {
                t: hit.t,
                tri,
                b1,
                b2,
            })
        } else {
            None
        }
    }

    /// Whether anything lies on the segment from `a` to `b` (end points excluded by offsets
    /// along the normals `na`, `nb` toward each other).
    pub fn occluded(&self, a: Vec3, na: Vec3, b: Vec3, nb: Vec3) -> bool {
        let d = b - a;
        let a = a + na * self.eps * na.dot(d).signum();
        let b = b - nb * self.eps * nb.dot(d).signum();
        let d = b - a;
        let len = d.length();
        if len <= self.eps {
            return false;
        }
        let ray = Ray::new(a.into(), (d / len).into(), 0.0, len * (1.0 - 1e-4));
        !self
            .bvh
            .ray_traverse_miss(ray, |r, id| self.hit_distance(r, id))
    }

    /// Offsets a surface point off its triangle, to the side `dir` leaves from.
    pub fn offset(&self, p: Vec3, n: Vec3, dir: Vec3) -> Vec3 {
        p + n * (self.eps * n.dot(dir).signum())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

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
