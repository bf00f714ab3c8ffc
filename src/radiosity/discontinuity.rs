//! Discontinuity meshing (Heckbert 1992; Lischinski, Tampieri and Greenberg 1992): the lines
//! on the receiving triangles where the direct light from an area emitter changes its form.
//! Where an occluder edge and an emitter vertex align (EV events) or an occluder vertex and
//! an emitter edge (VE events), a point of the receiver starts or stops seeing a piece of the
//! emitter: the radiance's derivative jumps there (D1: the umbra's and the penumbra's
//! boundaries). Where an occluder edge lies on the receiver (a block standing on the floor)
//! the radiance itself jumps (D0). [`lines`] finds these lines, clipped to each receiving
//! triangle and kept only where the event is seen (the ray from the receiver point through
//! the occluder's edge or vertex to the emitter is otherwise unblocked), and
//! [`super::mesh::Mesh::cut`] splits the elements along them before the solve, so that
//! element edges (and the Gouraud display's kinks) follow them. EEE events (three edges, on
//! quadric surfaces) are left out, as most discontinuity meshers leave them out.

use crate::scene::Frame;
use crate::trace::Tracer;
use glam::Vec3;
use serde::Serialize;
use std::collections::HashMap;

/// The order of a discontinuity: D0 (the radiance jumps) or D1 (its derivative does).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Order {
    D0,
    D1,
}

/// A discontinuity line on one receiving triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    /// The scene triangle it lies on.
    pub tri: u32,
    pub a: Vec3,
    pub b: Vec3,
    pub order: Order,
}

/// Events times receivers tested at most: past this (a big mesh) no line is traced and the
/// meshing is what adaptive refinement makes of it (docs/radiosity.md).
pub const MAX_TESTS: usize = 20_000_000;

/// Visibility samples along a line, at most (one per half element at least).
const MAX_SAMPLES: usize = 64;

/// An edge of the welded mesh: its end points and the triangles that hold it.
struct Edge {
    a: Vec3,
    b: Vec3,
    tris: Vec<u32>,
}

fn weld(frame: &Frame, keep: impl Fn(usize) -> bool) -> Vec<Edge> {
    let bits = |p: Vec3| p.to_array().map(f32::to_bits);
    let mut map: HashMap<([u32; 3], [u32; 3]), usize> = HashMap::new();
    let mut edges: Vec<Edge> = Vec::new();
    for (i, t) in frame.tris.iter().enumerate() {
        if !keep(i) || frame.areas[i].is_nan() || frame.areas[i] <= 0.0 {
            continue;
        }
        for k in 0..3 {
            let (p, q) = (t[k], t[(k + 1) % 3]);
            let (kp, kq) = (bits(p), bits(q));
            let key = if kp <= kq { (kp, kq) } else { (kq, kp) };
            let id = *map.entry(key).or_insert_with(|| {
                edges.push(Edge {
                    a: p,
                    b: q,
                    tris: Vec::new(),
                });
                edges.len() - 1
            });
            edges[id].tris.push(i as u32);
        }
    }
    edges
}

/// Whether triangle `i` is an area emitter's.
fn emits(frame: &Frame, i: usize) -> bool {
    frame.emission(i).max_element() > 0.0
}

/// Whether an edge is a real edge of its surface: not the diagonal between two coplanar
/// triangles (a quad's), where nothing starts or stops.
fn is_crease(frame: &Frame, e: &Edge) -> bool {
    match e.tris[..] {
        [s, t] => frame.normals[s as usize].dot(frame.normals[t as usize]) < 0.9999,
        _ => true,
    }
}

/// The emitter's outline (edges held by one emitting triangle of their plane), each with the
/// emitter's normal, and its corners.
/// Edges (ends and normal) and corners (point and normal) of the emitters' outline.
type Outline = (Vec<(Vec3, Vec3, Vec3)>, Vec<(Vec3, Vec3)>);

fn emitter_outline(frame: &Frame) -> Outline {
    let mut outline = Vec::new();
    let mut corners: Vec<(Vec3, Vec3)> = Vec::new();
    for e in weld(frame, |i| emits(frame, i)) {
        if !is_crease(frame, &e) {
            continue;
        }
        let n = frame.normals[e.tris[0] as usize];
        outline.push((e.a, e.b, n));
        for p in [e.a, e.b] {
            if !corners.iter().any(|c| c.0 == p && c.1.dot(n) > 0.9999) {
                corners.push((p, n));
            }
        }
    }
    (outline, corners)
}

/// A receiving triangle: its corners and front normal.
#[derive(Clone, Copy)]
struct Receiver {
    tri: u32,
    c: [Vec3; 3],
    n: Vec3,
}

impl Receiver {
    /// Height of `p` above the triangle's plane.
    fn h(&self, p: Vec3) -> f32 {
        (p - self.c[0]).dot(self.n)
    }

    /// Clips segment (a, b) of the plane to the triangle (its three inward half-planes).
    fn clip(&self, mut a: Vec3, mut b: Vec3) -> Option<(Vec3, Vec3)> {
        for k in 0..3 {
            let (p, q) = (self.c[k], self.c[(k + 1) % 3]);
            let inward = self.n.cross(q - p);
            let (da, db) = ((a - p).dot(inward), (b - p).dot(inward));
            match (da >= 0.0, db >= 0.0) {
                (true, true) => {}
                (false, false) => return None,
                (true, false) => b = a + (b - a) * (da / (da - db)),
                (false, true) => a = a + (b - a) * (da / (da - db)),
            }
        }
        Some((a, b))
    }
}

/// Clips the parameter range of a linear function `f(t) = f0 + t (f1 - f0)`, t in [lo, hi],
/// to where `f >= min` (`above`) or `f <= max`.
fn clip_range(lo: f32, hi: f32, f0: f32, f1: f32, bound: f32, above: bool) -> Option<(f32, f32)> {
    let (g0, g1) = if above {
        (f0 - bound, f1 - bound)
    } else {
        (bound - f0, bound - f1)
    };
    // g(t) >= 0 wanted.
    let (mut lo, mut hi) = (lo, hi);
    if g0 >= 0.0 && g1 >= 0.0 {
        return Some((lo, hi));
    }
    if g0 < 0.0 && g1 < 0.0 {
        return None;
    }
    let t = g0 / (g0 - g1);
    if g0 < 0.0 {
        lo = lo.max(t);
    } else {
        hi = hi.min(t);
    }
    (lo < hi).then_some((lo, hi))
}

/// The point of line (p, q) closest to line (r, s): where a ray through the receiver point
/// and the emitter meets the occluder's edge (or the emitter's edge).
fn closest_on(p: Vec3, q: Vec3, r: Vec3, s: Vec3) -> Vec3 {
    let (d1, d2, w) = (q - p, s - r, p - r);
    let (a, b, c) = (d1.dot(d1), d1.dot(d2), d2.dot(d2));
    let (d, e) = (d1.dot(w), d2.dot(w));
    let den = a * c - b * b;
    if den.abs() <= 1e-12 * a * c {
        return p;
    }
    p + d1 * ((b * e - c * d) / den)
}

/// The event that makes a line: an emitter vertex and an occluder edge, or an occluder vertex
/// and an emitter edge.
#[derive(Clone, Copy)]
enum Event {
    Ev {
        v: Vec3,
        ne: Vec3,
        a: Vec3,
        b: Vec3,
        /// The normals of the edge's triangles (the one twice on an open edge).
        faces: [Vec3; 2],
    },
    Ve {
        w: Vec3,
        a: Vec3,
        b: Vec3,
        ne: Vec3,
    },
}

impl Event {
    /// The event's line on receiver `r`, unclipped, and whether the occluder lies on it (D0).
    fn project(&self, r: &Receiver) -> Option<(Vec3, Vec3, Order)> {
        const NEAR: f32 = 1e-4;
        match *self {
            Event::Ev { v, ne, a, b, faces } => {
                let hv = r.h(v);
                if hv <= NEAR {
                    return None;
                }
                // The part of the edge in front of the emitter, and between the emitter's
                // vertex and the receiver's plane (height over hv in [0, 1)).
                let (fa, fb) = ((a - v).dot(ne), (b - v).dot(ne));
                let (lo, hi) = clip_range(0.0, 1.0, fa, fb, NEAR * hv, true)?;
                let (ra, rb) = (r.h(a) / hv, r.h(b) / hv);
                let (lo, hi) = clip_range(lo, hi, ra, rb, -NEAR, true)?;
                let (lo, hi) = clip_range(lo, hi, ra, rb, 1.0 - 1e-3, false)?;
                let at = |t: f32| {
                    let p = a + (b - a) * t;
                    let ratio = (ra + (rb - ra) * t).max(0.0);
                    v + (p - v) / (1.0 - ratio)
                };
                let on = ra.abs() < NEAR && rb.abs() < NEAR;
                // An edge of the receiver's own plane (its own, a coplanar neighbour's) is no
                // event: only an occluder standing on the receiver is.
                if on && faces.iter().all(|f| f.dot(r.n).abs() > 0.9999) {
                    return None;
                }
                Some((at(lo), at(hi), if on { Order::D0 } else { Order::D1 }))
            }
            Event::Ve { w, a, b, ne } => {
                let hw = r.h(w);
                if hw <= NEAR || (w - a).dot(ne) <= NEAR {
                    return None;
                }
                // The part of the emitter's edge above the occluder's vertex.
                let (ha, hb) = (r.h(a), r.h(b));
                let (lo, hi) = clip_range(0.0, 1.0, ha, hb, hw * (1.0 + 1e-3), true)?;
                let at = |t: f32| {
                    let p = a + (b - a) * t;
                    let h = ha + (hb - ha) * t;
                    p + (w - p) * (h / (h - hw))
                };
                Some((at(lo), at(hi), Order::D1))
            }
        }
    }

    /// Whether receiver point `x` lies on the event as seen: the emitter point the event
    /// passes through is hidden on one side of the line (`across`, a small step in the plane)
    /// and seen on the other. Testing the two sides, not the grazing ray itself, keeps lines
    /// inside solids (a floor under a block) and rays that merely touch an edge out.
    fn seen(&self, x: Vec3, n: Vec3, across: Vec3, tracer: &Tracer) -> bool {
        let (g, ne) = match *self {
            Event::Ev { v, ne, .. } => (v, ne),
            Event::Ve { w, a, b, ne } => (closest_on(a, b, x, w), ne),
        };
        // Both ways: a ray may pass a face it leaves from behind.
        let sees = |p: Vec3| !(tracer.occluded(p, n, g, ne) || tracer.occluded(g, ne, p, n));
        sees(x + across) != sees(x - across)
    }
}

/// The discontinuity lines of `frame`'s direct light from its area emitters, on every
/// triangle that reflects, each kept where its event is seen (sampled at least every half
/// `spacing`). Empty without an area emitter, or past [`MAX_TESTS`].
pub fn lines(frame: &Frame, tracer: &Tracer, spacing: f32) -> Vec<Line> {
    let (outline, corners) = emitter_outline(frame);
    if outline.is_empty() {
        return Vec::new();
    }
    let emits = |i: usize| emits(frame, i);
    let occluders: Vec<Edge> = weld(frame, |i| !emits(i))
        .into_iter()
        .filter(|e| is_crease(frame, e))
        .collect();
    let mut occluder_corners: Vec<Vec3> = Vec::new();
    {
        let mut seen = std::collections::HashSet::new();
        for e in &occluders {
            for p in [e.a, e.b] {
                if seen.insert(p.to_array().map(f32::to_bits)) {
                    occluder_corners.push(p);
                }
            }
        }
    }
    let receivers: Vec<Receiver> = (0..frame.tris.len())
        .filter(|&i| !emits(i) && frame.areas[i] > 0.0 && frame.albedo(i).max_element() > 0.0)
        .map(|i| Receiver {
            tri: i as u32,
            c: frame.tris[i],
            n: frame.normals[i],
        })
        .collect();
    // Counted before any event is made: a scene of many emitters and edges gets no lines
    // rather than a vector of billions of events.
    let n_events = corners
        .len()
        .saturating_mul(occluders.len())
        .saturating_add(occluder_corners.len().saturating_mul(outline.len()));
    if n_events
        .saturating_add(frame.tris.len())
        .saturating_mul(receivers.len())
        > MAX_TESTS
    {
        return Vec::new();
    }
    let mut events = Vec::with_capacity(n_events);
    for &(v, ne) in &corners {
        for e in &occluders {
            let n = |k: usize| frame.normals[e.tris[k.min(e.tris.len() - 1)] as usize];
            events.push(Event::Ev {
                v,
                ne,
                a: e.a,
                b: e.b,
                faces: [n(0), n(1)],
            });
        }
    }
    for &w in &occluder_corners {
        for &(a, b, ne) in &outline {
            events.push(Event::Ve { w, a, b, ne });
        }
    }
    use rayon::prelude::*;
    let spacing = spacing.max(1e-6);
    receivers
        .par_iter()
        .flat_map_iter(|r| {
            let mut out = Vec::new();
            for ev in &events {
                let Some((a, b, order)) = ev.project(r) else {
                    continue;
                };
                let Some((a, b)) = r.clip(a, b) else {
                    continue;
                };
                let len = (b - a).length();
                if len.is_nan() || len <= 1e-3 * spacing || !len.is_finite() {
                    continue;
                }
                // Keep the runs of samples that see the event.
                let k = ((2.0 * len / spacing).ceil() as usize).clamp(2, MAX_SAMPLES);
                let at = |i: usize| a + (b - a) * (0.001 + 0.998 * i as f32 / k as f32);
                let across = r.n.cross(b - a).normalize() * (0.01 * spacing);
                let mut run: Option<usize> = None;
                for i in 0..=k {
                    let seen = ev.seen(at(i), r.n, across, tracer);
                    match (seen, run) {
                        (true, None) => run = Some(i),
                        (false, Some(s)) => {
                            if i - 1 > s {
                                out.push(Line {
                                    tri: r.tri,
                                    a: at(s),
                                    b: at(i - 1),
                                    order,
                                });
                            }
                            run = None;
                        }
                        _ => {}
                    }
                }
                if let Some(s) = run {
                    if k > s {
                        out.push(Line {
                            tri: r.tri,
                            a: if s == 0 { a } else { at(s) },
                            b,
                            order,
                        });
                    }
                }
            }
            // Occluders passing through the receiver (a block sunk into the floor): where
            // their faces cross its plane the radiance jumps (D0), with no edge to say so.
            for (i, t) in frame.tris.iter().enumerate() {
                if emits(i) || frame.areas[i].is_nan() || frame.areas[i] <= 0.0 || i as u32 == r.tri
                {
                    continue;
                }
                if frame.normals[i].dot(r.n).abs() > 0.9999 {
                    continue;
                }
                if let Some((a, b)) = crossing(r, t).and_then(|(a, b)| r.clip(a, b)) {
                    if (b - a).length() > 1e-3 * spacing {
                        out.push(Line {
                            tri: r.tri,
                            a,
                            b,
                            order: Order::D0,
                        });
                    }
                }
            }
            out
        })
        .collect()
}

/// Where triangle `t` passes through the plane of receiver `r` (its corners strictly on both
/// sides), or None.
fn crossing(r: &Receiver, t: &[Vec3; 3]) -> Option<(Vec3, Vec3)> {
    let h = t.map(|p| r.h(p));
    let scale = (t[1] - t[0]).length().max((t[2] - t[0]).length());
    let tiny = 1e-5 * scale;
    if h.iter().all(|&x| x > -tiny) || h.iter().all(|&x| x < tiny) {
        return None;
    }
    let mut pts = Vec::with_capacity(2);
    for k in 0..3 {
        let (p, q, hp, hq) = (t[k], t[(k + 1) % 3], h[k], h[(k + 1) % 3]);
        if (hp < 0.0) != (hq < 0.0) {
            pts.push(p + (q - p) * (hp / (hp - hq)));
        }
    }
    match pts[..] {
        [a, b] => Some((a, b)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::radiosity::{self, first_mesh, mesh::Mesh, Meshing, RadiositySettings};
    use crate::scene::builtin;
    use glam::Vec2;

    fn cornell() -> (Frame, Tracer) {
        let f = builtin::load("cornell").unwrap().unwrap().at(0.0);
        let t = Tracer::new(&f);
        (f, t)
    }

    const FLOOR: f32 = -1.0;

    /// Convex hull (Andrew's monotone chain), counter-clockwise.
    fn hull(mut p: Vec<Vec2>) -> Vec<Vec2> {
        p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
        let cross = |o: Vec2, a: Vec2, b: Vec2| (a - o).perp_dot(b - o);
        let mut h: Vec<Vec2> = Vec::new();
        for pass in 0..2 {
            let start = h.len();
            let it: Box<dyn Iterator<Item = &Vec2>> = if pass == 0 {
                Box::new(p.iter())
            } else {
                Box::new(p.iter().rev())
            };
            for &q in it {
                while h.len() >= start + 2 && cross(h[h.len() - 2], h[h.len() - 1], q) <= 0.0 {
                    h.pop();
                }
                h.push(q);
            }
            h.pop();
        }
        h
    }

    fn inside(poly: &[Vec2], q: Vec2, margin: f32) -> bool {
        (0..poly.len()).all(|k| {
            let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
            (b - a).perp_dot(q - a) / (b - a).length() > margin
        })
    }

    /// Points (x, z) on the floor along the short block's umbra and penumbra boundaries,
    /// worked out here by projection alone: the block's shadow from each corner of the light
    /// is the hull of its top corners projected from that corner and its base corners; the
    /// umbra is where all four shadows overlap, the penumbra where any one falls. Each point
    /// comes with its boundary's unit normal in the floor.
    fn short_block_boundaries(f: &Frame) -> Vec<(Vec2, Vec2)> {
        // The light's corners and the short block's top corners (its top face at y = -0.4).
        let mut light: Vec<Vec3> = Vec::new();
        let mut top: Vec<Vec3> = Vec::new();
        for (i, t) in f.tris.iter().enumerate() {
            let bucket = if f.emission(i).max_element() > 0.0 {
                &mut light
            } else if t.iter().all(|p| (p.y + 0.4).abs() < 1e-4) && f.normals[i].y > 0.99 {
                &mut top
            } else {
                continue;
            };
            for &p in t {
                if !bucket.iter().any(|q| (*q - p).length() < 1e-5) {
                    bucket.push(p);
                }
            }
        }
        assert_eq!((light.len(), top.len()), (4, 4), "light and block corners");
        let shadows: Vec<Vec<Vec2>> = light
            .iter()
            .map(|&l| {
                let mut pts: Vec<Vec2> = top.iter().map(|p| Vec2::new(p.x, p.z)).collect();
                for &p in &top {
                    let q = l + (p - l) * ((l.y - FLOOR) / (l.y - p.y));
                    pts.push(Vec2::new(q.x, q.z));
                }
                hull(pts)
            })
            .collect();
        let base: Vec<Vec2> = hull(top.iter().map(|p| Vec2::new(p.x, p.z)).collect());
        let mut out = Vec::new();
        for (k, s) in shadows.iter().enumerate() {
            for e in 0..s.len() {
                let (a, b) = (s[e], s[(e + 1) % s.len()]);
                let n = (b - a).perp().normalize();
                let steps = ((b - a).length() / 0.01) as usize;
                for i in 1..steps {
                    let q = a + (b - a) * (i as f32 / steps as f32);
                    let others = shadows.iter().enumerate().filter(|&(j, _)| j != k);
                    let umbra = others.clone().all(|(_, o)| inside(o, q, 1e-4));
                    let penumbra = others.clone().all(|(_, o)| !inside(o, q, -1e-4));
                    let on_floor = q.x.abs() < 0.97 && q.y.abs() < 0.97;
                    if (umbra || penumbra) && on_floor && !inside(&base, q, 0.02) {
                        out.push((q, -n));
                    }
                }
            }
        }
        out
    }

    fn floor_edges(m: &Mesh) -> Vec<(Vec2, Vec2)> {
        let mut out = Vec::new();
        for i in 0..m.len() {
            let c = m.corners(i);
            if m.elems[i].normal.y > 0.99 && c.iter().all(|p| (p.y - FLOOR).abs() < 1e-4) {
                for k in 0..3 {
                    let (a, b) = (c[k], c[(k + 1) % 3]);
                    out.push((Vec2::new(a.x, a.z), Vec2::new(b.x, b.z)));
                }
            }
        }
        out
    }

    fn distance(q: Vec2, (a, b): (Vec2, Vec2)) -> f32 {
        let t = ((q - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
        (a + (b - a) * t - q).length()
    }

    /// The element edges of the discontinuity mesh follow the short block's umbra and
    /// penumbra on the floor (within the cut's snap of a tenth of an element, 0.015, plus
    /// float error); the adaptive mesh's edges do not.
    #[test]
    fn element_edges_follow_the_short_blocks_umbra_and_penumbra() {
        let (f, tr) = cornell();
        let bounds = short_block_boundaries(&f);
        assert!(bounds.len() > 100, "{} boundary points", bounds.len());
        let worst = |meshing| {
            let s = RadiositySettings {
                meshing,
                ..Default::default()
            };
            let edges = floor_edges(&first_mesh(&f, &tr, &s).0);
            let d: Vec<f32> = bounds
                .iter()
                .map(|&(q, _)| {
                    edges
                        .iter()
                        .map(|&e| distance(q, e))
                        .fold(f32::INFINITY, f32::min)
                })
                .collect();
            let mean = d.iter().sum::<f32>() / d.len() as f32;
            (d.iter().copied().fold(0.0, f32::max), mean)
        };
        let (cut, cut_mean) = worst(Meshing::Discontinuity);
        let (plain, plain_mean) = worst(Meshing::Adaptive);
        println!(
            "{} points: farthest from an edge {cut:.4} (mean {cut_mean:.4}) discontinuity, \
             {plain:.4} (mean {plain_mean:.4}) adaptive",
            bounds.len()
        );
        // Measured: 398 points, at most 0.0091 (mean 0.0009) from an edge of the cut mesh,
        // 0.036 (mean 0.0095) of the adaptive one's first mesh.
        assert!(
            cut < 0.015,
            "a boundary point is {cut} from every element edge"
        );
        assert!(
            plain > 3.0 * cut && plain_mean > 5.0 * cut_mean,
            "the adaptive mesh follows the boundaries as well ({plain}, mean {plain_mean})"
        );
    }

    /// The direct light's radiance at floor point `x` (albedo `rho`), from 32x32 points on each emitting
    /// triangle with a shadow ray each: the reference the meshes are measured against.
    fn direct_at(f: &Frame, tr: &Tracer, x: Vec3, rho: Vec3) -> f32 {
        let n = Vec3::Y;
        let mut e = Vec3::ZERO;
        for (i, t) in f.tris.iter().enumerate() {
            let le = f.emission(i);
            if le.max_element() <= 0.0 {
                continue;
            }
            let (ne, area, k) = (f.normals[i], f.areas[i], 32);
            for a in 0..k {
                for b in 0..k {
                    let (mut u, mut v) = ((a as f32 + 0.5) / k as f32, (b as f32 + 0.5) / k as f32);
                    if u + v > 1.0 {
                        (u, v) = (1.0 - u, 1.0 - v);
                    }
                    let y = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v;
                    let d = y - x;
                    let r2 = d.length_squared();
                    let g = (n.dot(d) * -ne.dot(d)).max(0.0) / (r2 * r2);
                    if g > 0.0 && !tr.occluded(x, n, y, ne) {
                        e += le * g * area / (k * k) as f32;
                    }
                }
            }
        }
        crate::math::luminance(rho * e / std::f32::consts::PI)
    }

    /// The solution's first bounce shown at floor point `x` (Gouraud, as displayed).
    fn shown_at(sol: &radiosity::Solution, corners: &[[Vec3; 3]], x: Vec3) -> f32 {
        for (i, e) in sol.mesh.elems.iter().enumerate() {
            if e.normal.y < 0.99 {
                continue;
            }
            let [a, b, c] = sol.mesh.corners(i);
            if (a.y - FLOOR).abs() > 1e-4 {
                continue;
            }
            let area = |p: Vec3, q: Vec3, r: Vec3| (q - p).cross(r - p).dot(Vec3::Y);
            let whole = area(a, b, c);
            let (wa, wb, wc) = (
                area(x, b, c) / whole,
                area(a, x, c) / whole,
                area(a, b, x) / whole,
            );
            if wa >= -1e-5 && wb >= -1e-5 && wc >= -1e-5 {
                let v = corners[i][0] * wa + corners[i][1] * wb + corners[i][2] * wc;
                return crate::math::luminance(v);
            }
        }
        f32::NAN
    }

    /// Near the short block's shadow boundaries (bands 0.02 and 0.05 to either side) the first
    /// bounce of a progressive solve on the discontinuity mesh is closer to the reference
    /// than on the adaptive mesh with as many elements.
    #[test]
    fn the_first_bounce_near_shadow_boundaries_is_closer_than_adaptive_meshings() {
        let (f, tr) = cornell();
        let bounds = short_block_boundaries(&f);
        let points: Vec<Vec3> = bounds
            .iter()
            .step_by(3)
            .flat_map(|&(q, n)| [-0.05, -0.02, 0.02, 0.05].map(move |d| q + n * d))
            .filter(|q| q.x.abs() < 0.99 && q.y.abs() < 0.99)
            .map(|q| Vec3::new(q.x, FLOOR + 1e-4, q.y))
            .collect();
        let floor = (0..f.tris.len())
            .find(|&i| f.normals[i].y > 0.99 && f.tris[i][0].y == FLOOR)
            .expect("the floor");
        let rho = f.albedo(floor);
        let reference: Vec<f32> = points.iter().map(|&x| direct_at(&f, &tr, x, rho)).collect();
        let error = |meshing, budget| {
            let s = RadiositySettings {
                meshing,
                max_elements: budget,
                ..Default::default()
            };
            let sol = radiosity::solve(&f, &tr, &s);
            let corners = sol.mesh.corner_values(&f, &sol.direct);
            let (mut num, mut den) = (0.0f64, 0.0f64);
            for (&x, &r) in points.iter().zip(&reference) {
                let got = shown_at(&sol, &corners, x);
                assert!(got.is_finite(), "no floor element holds {x}");
                num += ((got - r) as f64).powi(2);
                den += (r as f64).powi(2);
            }
            ((num / den).sqrt(), sol.stats.elements)
        };
        let (cut, n_cut) = error(Meshing::Discontinuity, 6000);
        let (plain, n_plain) = error(Meshing::Adaptive, n_cut);
        println!(
            "{} points: relative RMS error {cut:.4} discontinuity ({n_cut} elements), \
             {plain:.4} adaptive ({n_plain})",
            points.len()
        );
        assert!(
            n_plain.abs_diff(n_cut) * 50 <= n_cut,
            "{n_plain} against {n_cut} elements"
        );
        // Measured: 525 points, 0.082 against 0.176, 6002 elements each.
        assert!(cut < 0.7 * plain, "{cut} against {plain}");
    }

    /// Past `MAX_TESTS` (the atrium: 133,852 triangles) no line is traced, and no event is
    /// made first: the answer comes at once rather than after billions of events.
    #[test]
    fn a_big_mesh_gets_no_lines_instead_of_a_hang() {
        let f = builtin::load("atrium").unwrap().unwrap().at(0.0);
        let tr = Tracer::new(&f);
        let start = std::time::Instant::now();
        assert!(lines(&f, &tr, 0.5).is_empty());
        // Measured: under 0.4 s with the scene load; the bound only catches a hang.
        let s = start.elapsed().as_secs_f64();
        assert!(s < 10.0, "{s} s");
    }
}
