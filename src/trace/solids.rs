//! Solids a light path cannot be inside: closed meshes (`scene::culling::is_closed`: welded,
//! every edge paired, positive volume, faces out) that do not hold the camera. Their inside is
//! hidden from every camera point by their own faces, so light that is there (the back-facing
//! twin of a double-sided emitting face, `Scene::add_back_emitters`, lines a closed lamp's
//! inside and shines into it; a ray offset through a wall thinner than the tracer's offset
//! lands in it) reaches nothing the frame shows. In an albedo-1 solid it never ends either:
//! such paths bounced to the depth limit, their power growing by 1/q a bounce, and their VPLs
//! leaked through the ISMs (docs/math.md, "Light that cannot get out").

use crate::scene::Frame;
use glam::Vec3;

/// Per triangle: +1 a face of a solid (out is its front), -1 the back-facing emitting twin of
/// one (out is its back), 0 neither.
#[derive(Clone, Debug, PartialEq)]
pub struct Solids {
    side: Vec<i8>,
}

impl Solids {
    /// The solids of `frame` that do not hold its camera; None if there are none.
    pub fn of(frame: &Frame) -> Option<Solids> {
        let eye = frame.camera.position;
        let mut side = vec![0i8; frame.tris.len()];
        let mut any = false;
        // (An instance that names triangles the frame does not hold is left out.)
        let count = frame.tris.len();
        let held = |i: &&crate::scene::culling::Instance| i.tris.end as usize <= count;
        for i in frame.instances.iter().filter(|i| i.closed).filter(held) {
            let around = eye.cmpge(i.lo).all() && eye.cmple(i.hi).all();
            if around && holds(frame, i.tris.clone(), eye) {
                continue;
            }
            for t in i.tris.clone() {
                side[t as usize] = 1;
            }
            any = true;
        }
        if !any {
            return None;
        }
        // The twins follow every instance's triangles, one for each triangle of a
        // double-sided emitting material, in order, its corners (a, c, b) moved behind it.
        let first = frame
            .instances
            .iter()
            .map(|i| i.tris.end)
            .max()
            .unwrap_or(0) as usize;
        // `add_back_emitters` moves them by 1e-4 of the scene's size.
        let (lo, hi) = frame.bounds();
        let gap = 1e-4 * (hi - lo).max_element();
        let two_sided = |t: usize| {
            let m = &frame.materials[frame.tri_material[t] as usize];
            m.double_sided && m.emission.max_element() > 0.0
        };
        let parents = (0..first).filter(|&t| two_sided(t));
        for (twin, parent) in (first..frame.tris.len()).zip(parents) {
            let ([a, _, _], [ta, _, _]) = (frame.tris[parent], frame.tris[twin]);
            let near = (ta - a).length() <= 1.5 * gap;
            let opposite = frame.normals[twin].dot(frame.normals[parent]) < 0.0;
            if near && opposite && side[parent] == 1 {
                side[twin] = -1;
            }
        }
        Some(Solids { side })
    }

    /// Whether a ray along `dir` that strikes triangle `tri` (geometric normal `ng`) comes from
    /// inside a solid: it meets a face of one from behind, or a twin from its front.
    pub fn struck_from_inside(&self, tri: u32, ng: Vec3, dir: Vec3) -> bool {
        let s = self.side[tri as usize];
        s != 0 && (ng * s as f32).dot(dir) > 0.0
    }

    /// Whether light that triangle `tri` emits from its front goes into a solid (a twin's).
    pub fn emits_inside(&self, tri: u32) -> bool {
        self.side[tri as usize] < 0
    }
}

/// Whether the closed triangles `tris` of `frame` hold point `p`: an odd number of them cross
/// a ray from it (along a direction no axis-aligned face lies along).
fn holds(frame: &Frame, tris: std::ops::Range<u32>, p: Vec3) -> bool {
    let d = Vec3::new(0.5773, 0.5780, 0.5766).normalize();
    let crossings = tris
        .filter(|&t| {
            let [a, b, c] = frame.tris[t as usize];
            let (e1, e2) = (b - a, c - a);
            let h = d.cross(e2);
            let det = e1.dot(h);
            if det.abs() < 1e-20 {
                return false;
            }
            let s = p - a;
            let u = s.dot(h) / det;
            let q = s.cross(e1);
            let v = d.dot(q) / det;
            u >= 0.0 && v >= 0.0 && u + v <= 1.0 && e2.dot(q) / det > 0.0
        })
        .count();
    crossings % 2 == 1
}
