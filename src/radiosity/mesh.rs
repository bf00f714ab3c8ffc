//! Meshing: the frame's triangles cut into elements by longest-edge bisection (Rivara's
//! LEPP refinement). A split always cuts an edge in every element that holds it, so the mesh
//! stays conforming: no element has a vertex in the middle of a neighbour's edge (no
//! T-vertices), and Gouraud shading at shared vertices has no cracks. Elements keep the scene
//! triangle they came from. Shadow boundaries are followed by adaptive refinement
//! ([`Mesh::refine_adaptive`]) and, with discontinuity meshing, by cuts along them first
//! ([`Mesh::cut`], lines from [`super::discontinuity`]).

use crate::scene::Frame;
use glam::Vec3;
use std::collections::HashMap;

/// One element: a triangle of the mesh, one-sided (it faces along `normal`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Element {
    /// Vertex indices, counter-clockwise seen from the front.
    pub v: [u32; 3],
    /// The scene triangle it came from.
    pub source: u32,
    pub normal: Vec3,
    pub area: f32,
    /// The patch it lies in (see [`Mesh::mark_patches`]).
    pub patch: u32,
}

/// A coarser triangle made of elements: progressive refinement shoots its dim light from
/// patches, the lecture's patches-and-elements (substructuring) scheme.
#[derive(Clone, Copy, Debug)]
pub struct Patch {
    pub corners: [Vec3; 3],
    pub normal: Vec3,
    pub area: f32,
}

/// Points (barycentrics) of an element at which [`Mesh::open_fractions`] looks out.
const OPEN_POINTS: [[f32; 2]; 4] = [
    [1.0 / 3.0, 1.0 / 3.0],
    [2.0 / 3.0, 1.0 / 6.0],
    [1.0 / 6.0, 2.0 / 3.0],
    [1.0 / 6.0, 1.0 / 6.0],
];
/// Rays from each of [`OPEN_POINTS`].
const OPEN_RAYS: u32 = 8;

/// A conforming triangle mesh of elements.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub verts: Vec<Vec3>,
    pub elems: Vec<Element>,
    /// The patches elements lie in: each element of the scene's own triangles until
    /// [`Mesh::mark_patches`]; an element split later stays in its patch.
    pub patches: Vec<Patch>,
    /// Elements holding each edge (key: smaller vertex first).
    edges: HashMap<(u32, u32), Vec<u32>>,
    /// Midpoint vertex of each edge split so far.
    midpoints: HashMap<(u32, u32), u32>,
    /// Per element, the share of it that is open ([`Mesh::open_fractions`]): what
    /// [`Mesh::corner_values`] weighs it by. Empty: every element open (not measured).
    pub open: Vec<f32>,
    /// The radius over which [`Mesh::corner_values`] averages a vertex's value (0: the
    /// elements that hold the vertex). Hierarchical radiosity's leaves take their light mostly
    /// from links at their ancestors' level, constant over each and stepping at their borders;
    /// its solve sets this to a third of its top patches' size.
    pub smooth: f32,
}

fn key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// Whether two elements' values may be averaged at a vertex they share: the same plane
/// direction and triangles of the same material (so colours do not bleed around corners).
fn alike(frame: &Frame, a: &Element, b: &Element) -> bool {
    a.normal.dot(b.normal) > 0.99
        && frame.tri_material[a.source as usize] == frame.tri_material[b.source as usize]
}

impl Mesh {
    /// The frame's triangles as elements, vertices welded where positions are equal.
    /// Degenerate triangles (zero area) get no element.
    pub fn from_frame(frame: &Frame) -> Mesh {
        let mut m = Mesh::default();
        let mut index: HashMap<[u32; 3], u32> = HashMap::new();
        for (i, t) in frame.tris.iter().enumerate() {
            if frame.areas[i] <= 0.0 || !frame.areas[i].is_finite() {
                continue;
            }
            let v = t.map(|p| {
                *index
                    .entry(p.to_array().map(f32::to_bits))
                    .or_insert_with(|| {
                        m.verts.push(p);
                        m.verts.len() as u32 - 1
                    })
            });
            if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
                continue;
            }
            m.push(v, i as u32, frame.normals[i]);
        }
        m
    }

    /// A mesh from triangles (corners, scene triangle, unit normal), welded where positions
    /// are equal. It may have T-vertices (hierarchical radiosity's leaves do).
    pub fn from_triangles(tris: &[([Vec3; 3], u32, Vec3)]) -> Mesh {
        let mut m = Mesh::default();
        let mut index: HashMap<[u32; 3], u32> = HashMap::new();
        for &(t, source, normal) in tris {
            let v = t.map(|p| {
                *index
                    .entry(p.to_array().map(f32::to_bits))
                    .or_insert_with(|| {
                        m.verts.push(p);
                        m.verts.len() as u32 - 1
                    })
            });
            m.push(v, source, normal);
        }
        m
    }

    /// The frame meshed to elements whose edges are at most `target` long, with at most
    /// `budget` elements.
    pub fn uniform(frame: &Frame, target: f32, budget: usize) -> Mesh {
        let mut m = Mesh::from_frame(frame);
        m.refine_to(target, budget);
        m
    }

    /// As [`Mesh::uniform`], with patches of edges at most `patch` long: the frame is meshed
    /// to `patch` first, those elements become the patches, and they are split on to `target`.
    pub fn uniform_with_patches(frame: &Frame, patch: f32, target: f32, budget: usize) -> Mesh {
        let mut m = Mesh::from_frame(frame);
        m.refine_to(patch, budget);
        m.mark_patches();
        m.refine_to(target, budget);
        m
    }

    /// Makes every element its own patch (elements split later stay in it).
    pub fn mark_patches(&mut self) {
        self.patches = (0..self.elems.len())
            .map(|e| Patch {
                corners: self.corners(e),
                normal: self.elems[e].normal,
                area: self.elems[e].area,
            })
            .collect();
        for (i, e) in self.elems.iter_mut().enumerate() {
            e.patch = i as u32;
        }
    }

    /// A new element, in a patch of its own.
    fn push(&mut self, v: [u32; 3], source: u32, normal: Vec3) -> u32 {
        let patch = self.patches.len() as u32;
        let id = self.push_in(v, source, normal, patch);
        self.patches.push(Patch {
            corners: self.corners(id as usize),
            normal,
            area: self.elems[id as usize].area,
        });
        id
    }

    fn push_in(&mut self, v: [u32; 3], source: u32, normal: Vec3, patch: u32) -> u32 {
        let id = self.elems.len() as u32;
        self.elems.push(Element {
            v,
            source,
            normal,
            area: 0.0,
            patch,
        });
        self.set(id, v);
        id
    }

    /// Sets element `id`'s vertices (its edges must not be in the map yet).
    fn set(&mut self, id: u32, v: [u32; 3]) {
        let e = &mut self.elems[id as usize];
        e.v = v;
        let [a, b, c] = v.map(|i| self.verts[i as usize]);
        e.area = 0.5 * (b - a).cross(c - a).length();
        for k in 0..3 {
            self.edges
                .entry(key(v[k], v[(k + 1) % 3]))
                .or_default()
                .push(id);
        }
    }

    fn unset(&mut self, id: u32) {
        let v = self.elems[id as usize].v;
        for k in 0..3 {
            if let Some(list) = self.edges.get_mut(&key(v[k], v[(k + 1) % 3])) {
                list.retain(|&x| x != id);
            }
        }
    }

    pub fn len(&self) -> usize {
        self.elems.len()
    }

    pub fn is_empty(&self) -> bool {
        self.elems.is_empty()
    }

    /// The element's corner positions.
    pub fn corners(&self, e: usize) -> [Vec3; 3] {
        self.elems[e].v.map(|i| self.verts[i as usize])
    }

    pub fn centroid(&self, e: usize) -> Vec3 {
        let [a, b, c] = self.corners(e);
        (a + b + c) / 3.0
    }

    fn edge_len2(&self, a: u32, b: u32) -> f32 {
        (self.verts[a as usize] - self.verts[b as usize]).length_squared()
    }

    /// The element's longest edge (ties broken by vertex index, so both sides agree).
    fn longest(&self, e: u32) -> (u32, u32) {
        let v = self.elems[e as usize].v;
        (0..3)
            .map(|k| key(v[k], v[(k + 1) % 3]))
            .max_by(|&(a, b), &(c, d)| {
                self.edge_len2(a, b)
                    .total_cmp(&self.edge_len2(c, d))
                    .then((a, b).cmp(&(c, d)))
            })
            .unwrap()
    }

    /// Longest edge length of element `e`.
    pub fn diameter(&self, e: usize) -> f32 {
        let (a, b) = self.longest(e as u32);
        self.edge_len2(a, b).sqrt()
    }

    /// Splits edge (a, b) at its midpoint in every element holding it. Returns the new
    /// elements (each split element keeps its index for one half).
    fn split_edge(&mut self, a: u32, b: u32) -> Vec<u32> {
        let k = key(a, b);
        let m = *self.midpoints.entry(k).or_insert_with(|| {
            self.verts
                .push((self.verts[a as usize] + self.verts[b as usize]) * 0.5);
            self.verts.len() as u32 - 1
        });
        self.split_edge_with(a, b, m)
    }

    /// Splits edge (a, b) at vertex `m` (a point on it) in every element holding it.
    fn split_edge_with(&mut self, a: u32, b: u32, m: u32) -> Vec<u32> {
        let k = key(a, b);
        let holders = self.edges.remove(&k).unwrap_or_default();
        let mut born = Vec::new();
        for id in holders {
            self.unset(id);
            let v = self.elems[id as usize].v;
            // Rotate so that the split edge is (v[i], v[i+1]).
            let i = (0..3)
                .find(|&i| key(v[i], v[(i + 1) % 3]) == k)
                .expect("edge map names an element holding the edge");
            let (x, y, z) = (v[i], v[(i + 1) % 3], v[(i + 2) % 3]);
            self.set(id, [x, m, z]);
            let (source, normal, patch) = {
                let e = &self.elems[id as usize];
                (e.source, e.normal, e.patch)
            };
            born.push(self.push_in([m, y, z], source, normal, patch));
        }
        born
    }

    /// Cuts the elements along discontinuity lines ([`super::discontinuity`]): every element
    /// edge a line crosses is split at the crossing, in every element holding it, so the mesh
    /// stays conforming and each line becomes a chain of element edges (after the first
    /// crossing, every element the line enters already has a corner on it). A line passing
    /// within `snap` of a vertex is taken to pass through it (no sliver elements; the chain is
    /// then off the line by at most `snap`). The line's ends become vertices first. Returns
    /// the vertices added.
    pub fn cut(&mut self, lines: &[super::discontinuity::Line], snap: f32) -> usize {
        if snap.is_nan() || snap <= 0.0 {
            return 0;
        }
        let mut of_source: HashMap<u32, Vec<u32>> = HashMap::new();
        for (i, e) in self.elems.iter().enumerate() {
            of_source.entry(e.source).or_default().push(i as u32);
        }
        let mut added = 0;
        for l in lines {
            // The line's ends become vertices (where no vertex or edge is within `snap`), so
            // the chain reaches them.
            for p in [l.a, l.b] {
                let Some(ids) = of_source.get(&l.tri) else {
                    break;
                };
                if let Some(born) = self.insert(ids, p, snap) {
                    for b in born {
                        let src = self.elems[b as usize].source;
                        of_source.entry(src).or_default().push(b);
                    }
                    added += 1;
                }
            }
            let d2 = l.b - l.a;
            // At most one split per element edge it can cross; the guard only stops a loop
            // that floating point might make.
            for _ in 0..100_000 {
                let Some(ids) = of_source.get(&l.tri) else {
                    break;
                };
                let mut hit = None;
                'scan: for &id in ids {
                    let e = &self.elems[id as usize];
                    let n = e.normal;
                    for k in 0..3 {
                        let (u, v) = (e.v[k], e.v[(k + 1) % 3]);
                        let p = self.verts[u as usize];
                        let d1 = self.verts[v as usize] - p;
                        let den = d1.cross(d2).dot(n);
                        let len = d1.length();
                        if den.abs() <= 1e-6 * len * d2.length() {
                            continue;
                        }
                        // An end within `snap` of the line: it passes through that vertex.
                        let off = |x: Vec3| (x - l.a).cross(d2).length() / d2.length();
                        if off(p) <= snap || off(p + d1) <= snap {
                            continue;
                        }
                        let w = l.a - p;
                        let t = w.cross(d2).dot(n) / den;
                        let s = w.cross(d1).dot(n) / den;
                        if (0.0..=1.0).contains(&s) && t * len > snap && (1.0 - t) * len > snap {
                            hit = Some((u, v, t));
                            break 'scan;
                        }
                    }
                }
                let Some((u, v, t)) = hit else {
                    break;
                };
                let (pu, pv) = (self.verts[u as usize], self.verts[v as usize]);
                let q = pu + (pv - pu) * t;
                self.verts.push(q);
                let m = self.verts.len() as u32 - 1;
                for b in self.split_edge_with(u, v, m) {
                    let src = self.elems[b as usize].source;
                    of_source.entry(src).or_default().push(b);
                }
                added += 1;
            }
        }
        added
    }

    /// Makes point `p` a vertex of the element of `ids` that holds it: the element is split in
    /// three at `p`, or the edge within `snap` of it is split at the nearest point; nothing
    /// when a vertex is within `snap` or no element holds it. Returns the new elements, or
    /// None when nothing was added.
    fn insert(&mut self, ids: &[u32], p: Vec3, snap: f32) -> Option<Vec<u32>> {
        let holder = ids.iter().copied().find(|&id| {
            let [a, b, c] = self.corners(id as usize);
            let n = self.elems[id as usize].normal;
            let side =
                |u: Vec3, v: Vec3| (v - u).cross(p - u).dot(n) >= -1e-6 * (v - u).length_squared();
            side(a, b) && side(b, c) && side(c, a)
        })?;
        let e = self.elems[holder as usize];
        let c = e.v.map(|v| self.verts[v as usize]);
        if c.iter().any(|&q| (q - p).length() <= snap) {
            return None;
        }
        for k in 0..3 {
            let (u, v) = (c[k], c[(k + 1) % 3]);
            let t = ((p - u).dot(v - u) / (v - u).length_squared()).clamp(0.0, 1.0);
            if (u + (v - u) * t - p).length() <= snap {
                let len = (v - u).length();
                if t * len <= snap || (1.0 - t) * len <= snap {
                    return None;
                }
                self.verts.push(u + (v - u) * t);
                let m = self.verts.len() as u32 - 1;
                return Some(self.split_edge_with(e.v[k], e.v[(k + 1) % 3], m));
            }
        }
        self.verts.push(p);
        let m = self.verts.len() as u32 - 1;
        let [a, b, cc] = e.v;
        self.unset(holder);
        self.set(holder, [a, b, m]);
        Some(vec![
            self.push_in([b, cc, m], e.source, e.normal, e.patch),
            self.push_in([cc, a, m], e.source, e.normal, e.patch),
        ])
    }

    /// Rivara's longest-edge propagation path: bisects element `e` (and, to keep the mesh
    /// conforming and its angles bounded, the neighbours along the path of increasing longest
    /// edges first). Returns the number of elements added.
    pub fn bisect(&mut self, e: u32) -> usize {
        let before = self.elems.len();
        let target_len = {
            let (a, b) = self.longest(e);
            self.edge_len2(a, b)
        };
        // Split until `e`'s longest edge got shorter (e keeps its index for one half).
        let mut guard = 0;
        loop {
            let (a, b) = self.longest(e);
            if self.edge_len2(a, b) < target_len || guard > 64 {
                break;
            }
            guard += 1;
            // Walk the path from e: neighbour across the longest edge, while the neighbour's
            // longest edge is longer.
            let mut cur = e;
            let mut steps = 0;
            loop {
                let (a, b) = self.longest(cur);
                let l = self.edge_len2(a, b);
                let next = self.edges[&(a, b)].iter().copied().find(|&n| {
                    n != cur && {
                        let (c, d) = self.longest(n);
                        (c, d) != (a, b) && self.edge_len2(c, d) > l
                    }
                });
                match next {
                    Some(n) if steps < 10_000 => {
                        cur = n;
                        steps += 1;
                    }
                    _ => {
                        self.split_edge(a, b);
                        break;
                    }
                }
            }
        }
        self.elems.len() - before
    }

    /// Bisects until every element's longest edge is at most `target`, or the mesh holds
    /// `budget` elements. Longest elements first.
    pub fn refine_to(&mut self, target: f32, budget: usize) {
        if target.is_nan() || target <= 0.0 {
            return;
        }
        loop {
            let mut todo: Vec<(f32, u32)> = (0..self.elems.len())
                .map(|e| (self.diameter(e), e as u32))
                .filter(|&(d, _)| d > target)
                .collect();
            if todo.is_empty() {
                return;
            }
            todo.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
            for (_, e) in todo {
                if self.elems.len() >= budget {
                    return;
                }
                if self.diameter(e as usize) > target {
                    self.bisect(e);
                }
            }
        }
    }

    /// Adaptive refinement: bisects elements whose radiance (luminance of `value`) differs
    /// from an edge neighbour on the same plane by more than `threshold` (absolute), largest
    /// difference first, while elements are larger than `min_diameter` and the mesh holds
    /// fewer than `budget` elements. Returns the number of elements split.
    pub fn refine_adaptive(
        &mut self,
        value: &[Vec3],
        threshold: f32,
        min_diameter: f32,
        budget: usize,
    ) -> usize {
        let lum: Vec<f32> = value.iter().map(|&v| crate::math::luminance(v)).collect();
        let mut worst = vec![0.0f32; self.elems.len()];
        for list in self.edges.values() {
            for (i, &p) in list.iter().enumerate() {
                for &q in &list[i + 1..] {
                    let (ep, eq) = (&self.elems[p as usize], &self.elems[q as usize]);
                    if ep.normal.dot(eq.normal) < 0.999 {
                        continue;
                    }
                    let d = (lum[p as usize] - lum[q as usize]).abs();
                    worst[p as usize] = worst[p as usize].max(d);
                    worst[q as usize] = worst[q as usize].max(d);
                }
            }
        }
        let mut todo: Vec<(f32, u32)> = worst
            .iter()
            .enumerate()
            .filter(|&(e, &d)| d > threshold && self.diameter(e) > min_diameter)
            .map(|(e, &d)| (d, e as u32))
            .collect();
        todo.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let mut split = 0;
        for (_, e) in todo {
            if self.elems.len() >= budget {
                break;
            }
            self.bisect(e);
            split += 1;
        }
        split
    }

    /// For each vertex, the elements that hold it.
    pub fn vertex_elements(&self) -> Vec<Vec<u32>> {
        let mut out = vec![Vec::new(); self.verts.len()];
        for (i, e) in self.elems.iter().enumerate() {
            for &v in &e.v {
                out[v as usize].push(i as u32);
            }
        }
        out
    }

    /// Per element, the share of its area that is open: of [`OPEN_POINTS`] points on it, those
    /// from which two or more of [`OPEN_RAYS`] cosine-distributed rays get out (meet no surface
    /// within the element's longest edge) and which lie in no solid (the first ray strikes
    /// none from inside: `Tracer::struck_inside_solid`). A covered element is one on which
    /// something lies: the ceiling behind a lamp mounted just under it, the floor under a box
    /// standing on it. No light reaches it and the camera never sees it, so its radiance
    /// (about 0, or a parent's in hierarchical radiosity) is not the light of the surface
    /// around it. A crease's elements stay open (half their rays get out), a corner's too
    /// (a quarter).
    pub fn open_fractions(&self, frame: &Frame, tracer: &crate::trace::Tracer) -> Vec<f32> {
        use rayon::prelude::*;
        (0..self.elems.len())
            .into_par_iter()
            .map(|e| {
                let n = self.elems[e].normal;
                let [a, b, c] = self.corners(e);
                let reach = self.diameter(e);
                let open = OPEN_POINTS
                    .iter()
                    .filter(|&&[u, v]| {
                        let x = a * (1.0 - u - v) + b * u + c * v;
                        // Stratified in the polar angle, a golden-ratio step in azimuth.
                        let ray = |k: u32| {
                            let uv = glam::Vec2::new(
                                (k as f32 + 0.5) / OPEN_RAYS as f32,
                                (k as f32 * 0.618_034 + u).fract(),
                            );
                            let w = crate::math::cosine_hemisphere(n, uv);
                            (tracer.offset(x, n, w), w)
                        };
                        // Inside a solid every ray strikes it from inside first, outside none
                        // does: the first ray, cast all the way, tells (and whether it gets
                        // out); the others stop at `reach`.
                        let (o, w) = ray(0);
                        let first = tracer.intersect(o, w, f32::INFINITY);
                        let inside = first.is_some_and(|h| {
                            tracer.struck_inside_solid(h.tri, frame.normals[h.tri as usize], w)
                        });
                        let out = usize::from(first.is_none_or(|h| h.t > reach))
                            + (1..OPEN_RAYS)
                                .filter(|&k| {
                                    let (o, w) = ray(k);
                                    tracer.intersect(o, w, reach).is_none()
                                })
                                .count();
                        !inside && out >= 2
                    })
                    .count();
                open as f32 / OPEN_POINTS.len() as f32
            })
            .collect()
    }

    /// Gouraud values: for each element corner, the mean of `value` over the elements around
    /// that vertex that lie in the same plane direction and came from a triangle of the same
    /// material (so colours do not bleed around corners), weighted by their area and by
    /// their open share ([`Mesh::open`]; all of them where none is open); with
    /// [`Mesh::smooth`], over those of the vertex's plane whose centroids lie within it,
    /// weighted by a tent too. Where the mesh
    /// is not conforming (hierarchical radiosity's leaves: an element's edge holds another
    /// element's corner, a T-vertex), the corner at the T-vertex takes the value the longer
    /// edge interpolates there, longest edges first, so the shading is continuous across every
    /// edge (a step there is a line in the image that the pixel grid samples differently in
    /// every frame of a moving camera).
    pub fn corner_values(&self, frame: &Frame, value: &[Vec3]) -> Vec<[Vec3; 3]> {
        let around = self.vertex_elements();
        let mut corners = self.gouraud(frame, value, &around);
        self.conform(frame, &mut corners, &around);
        corners
    }

    /// [`Mesh::corner_values`] before [`Mesh::conform`]: the (smoothed) means at each corner.
    /// `around`: [`Mesh::vertex_elements`].
    pub fn gouraud(&self, frame: &Frame, value: &[Vec3], around: &[Vec<u32>]) -> Vec<[Vec3; 3]> {
        use rayon::prelude::*;
        let broadcast: Vec<[Vec3; 3]> = value.iter().map(|&v| [v; 3]).collect();
        let mut corners = self.shared_corners(frame, &broadcast, around);
        if self.smooth <= 0.0 {
            return corners;
        }
        // Elements by cell of side `smooth` and by orientation and material, for the smoothed
        // means, computed once for each vertex and orientation (in parallel).
        let share = |o: usize| self.open.get(o).copied().unwrap_or(1.0);
        let cell = |q: Vec3| (q / self.smooth).floor().as_ivec3();
        let facing = |e: &Element| {
            let n = (e.normal * 64.0).round().as_ivec3();
            (n, frame.tri_material[e.source as usize])
        };
        let centroids: Vec<Vec3> = (0..self.elems.len()).map(|o| self.centroid(o)).collect();
        let mut grid: HashMap<(glam::IVec3, glam::IVec3, u32), Vec<u32>> = HashMap::new();
        for (o, e) in self.elems.iter().enumerate() {
            let (n, m) = facing(e);
            grid.entry((cell(centroids[o]), n, m))
                .or_default()
                .push(o as u32);
        }
        // One element for each vertex and orientation: the first that holds it.
        let mut keys: HashMap<(u32, glam::IVec3, u32), u32> = HashMap::new();
        for (i, e) in self.elems.iter().enumerate() {
            let (n, m) = facing(e);
            for &v in &e.v {
                keys.entry((v, n, m)).or_insert(i as u32);
            }
        }
        let keys: Vec<((u32, glam::IVec3, u32), u32)> = keys.into_iter().collect();
        let smoothed: HashMap<(u32, glam::IVec3, u32), Vec3> = keys
            .par_iter()
            .filter_map(|&((v, n, m), i)| {
                let (e, p) = (&self.elems[i as usize], self.verts[v as usize]);
                let (mut sum, mut w) = (Vec3::ZERO, 0.0f32);
                let k = cell(p);
                for dx in -1..=1 {
                    for dy in -1..=1 {
                        for dz in -1..=1 {
                            let at = (k + glam::IVec3::new(dx, dy, dz), n, m);
                            for &o in grid.get(&at).into_iter().flatten() {
                                let (eo, c) = (&self.elems[o as usize], centroids[o as usize]);
                                if !alike(frame, e, eo)
                                    || e.normal.dot(c - p).abs() > 1e-4 * self.smooth
                                {
                                    continue;
                                }
                                let t = (1.0 - (c - p).length() / self.smooth).max(0.0);
                                let a = eo.area * share(o as usize) * t;
                                sum += value[o as usize] * a;
                                w += a;
                            }
                        }
                    }
                }
                (w > 0.0).then(|| ((v, n, m), sum / w))
            })
            .collect();
        for (e, c) in self.elems.iter().zip(corners.iter_mut()) {
            let (n, m) = facing(e);
            for (v, c) in e.v.iter().zip(c.iter_mut()) {
                if let Some(&x) = smoothed.get(&(*v, n, m)) {
                    *c = x;
                }
            }
        }
        corners
    }

    /// Per-corner values made one per vertex: each corner takes the mean of the values that
    /// the elements around its vertex, in the same plane direction and of the same material
    /// ([`alike`]), hold there, weighted by their area and by their open share ([`Mesh::open`];
    /// all of them where none is open). A covered element's corners, dark, would otherwise ring
    /// its cover's outline. `around`: [`Mesh::vertex_elements`].
    pub fn shared_corners(
        &self,
        frame: &Frame,
        corners: &[[Vec3; 3]],
        around: &[Vec<u32>],
    ) -> Vec<[Vec3; 3]> {
        let share = |o: usize| self.open.get(o).copied().unwrap_or(1.0);
        self.elems
            .iter()
            .map(|e| {
                e.v.map(|v| {
                    let mean = |open: bool| {
                        let (mut sum, mut w) = (Vec3::ZERO, 0.0f32);
                        for &o in &around[v as usize] {
                            let eo = &self.elems[o as usize];
                            if alike(frame, e, eo) {
                                if let Some(j) = eo.v.iter().position(|&x| x == v) {
                                    let s = if open { share(o as usize) } else { 1.0 };
                                    sum += corners[o as usize][j] * eo.area * s;
                                    w += eo.area * s;
                                }
                            }
                        }
                        (w > 0.0).then(|| sum / w)
                    };
                    mean(true).or_else(|| mean(false)).unwrap_or(Vec3::ZERO)
                })
            })
            .collect()
    }

    /// Makes corner values continuous across T-vertices: where an element's edge holds
    /// another element's corner, that corner takes the value the longer edge interpolates
    /// there, longest edges first. `around`: [`Mesh::vertex_elements`].
    pub fn conform(&self, frame: &Frame, corners: &mut [[Vec3; 3]], around: &[Vec<u32>]) {
        // T-vertices lie at midpoints of longer edges (midpoint splits), of their halves and
        // so on: found by position, the midpoint computed as the split computed it.
        let bits = |p: Vec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
        let at: HashMap<[u32; 3], u32> = self
            .verts
            .iter()
            .enumerate()
            .map(|(i, &p)| (bits(p), i as u32))
            .collect();
        let mut order: Vec<u32> = (0..self.elems.len() as u32).collect();
        order.sort_by(|&a, &b| {
            let la = self.longest(a);
            let lb = self.longest(b);
            self.edge_len2(lb.0, lb.1)
                .total_cmp(&self.edge_len2(la.0, la.1))
        });
        for e in order {
            let el = &self.elems[e as usize];
            for i in 0..3 {
                let (a, b) = (el.v[i], el.v[(i + 1) % 3]);
                let (ca, cb) = (corners[e as usize][i], corners[e as usize][(i + 1) % 3]);
                // (a, b, their values), halved while a vertex sits at the midpoint.
                let mut stack = vec![(a, b, ca, cb, 0)];
                while let Some((a, b, ca, cb, depth)) = stack.pop() {
                    let mid = (self.verts[a as usize] + self.verts[b as usize]) * 0.5;
                    let Some(&m) = at.get(&bits(mid)) else {
                        continue;
                    };
                    if m == a || m == b || depth > 32 {
                        continue;
                    }
                    let cm = (ca + cb) * 0.5;
                    for &o in &around[m as usize] {
                        let eo = &self.elems[o as usize];
                        if o != e && alike(frame, el, eo) {
                            if let Some(j) = eo.v.iter().position(|&v| v == m) {
                                corners[o as usize][j] = cm;
                            }
                        }
                    }
                    stack.push((a, m, ca, cm, depth + 1));
                    stack.push((m, b, cm, cb, depth + 1));
                }
            }
        }
    }

    /// The elements as a frame (same camera and materials), for ray casting onto elements:
    /// a hit's triangle index is the element index.
    pub fn as_frame(&self, frame: &Frame) -> Frame {
        let tris: Vec<[Vec3; 3]> = (0..self.len()).map(|e| self.corners(e)).collect();
        Frame {
            time: frame.time,
            tri_material: self
                .elems
                .iter()
                .map(|e| frame.tri_material[e.source as usize])
                .collect(),
            normals: self.elems.iter().map(|e| e.normal).collect(),
            areas: self.elems.iter().map(|e| e.area).collect(),
            emitter_of_tri: vec![u32::MAX; tris.len()],
            // Drawn whole (the elements' raster passes leave nothing out).
            instances: Vec::new(),
            tris,
            // Double-sided: classical radiosity treats every surface as double-sided.
            materials: std::sync::Arc::new(
                frame
                    .materials
                    .iter()
                    .map(|m| crate::scene::Material {
                        double_sided: true,
                        ..m.clone()
                    })
                    .collect(),
            ),
            // Elements take their materials' factors (textures are not resolved per element).
            textures: frame.textures.clone(),
            attrs: None,
            camera: frame.camera,
            emitters: Default::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    /// No vertex lies strictly inside an element's edge (the Cornell box's input has none).
    fn assert_conforming(m: &Mesh) {
        for (e, el) in m.elems.iter().enumerate() {
            let [a, b, c] = m.corners(e);
            for (p, q) in [(a, b), (b, c), (c, a)] {
                for (vi, &x) in m.verts.iter().enumerate() {
                    if el.v.contains(&(vi as u32)) {
                        continue;
                    }
                    let d = q - p;
                    let t = (x - p).dot(d) / d.length_squared();
                    assert!(
                        !(t > 1e-4 && t < 1.0 - 1e-4 && (p + d * t - x).length() < 1e-6),
                        "T-vertex {vi} at {x} on element {e}'s edge"
                    );
                }
            }
        }
    }

    #[test]
    fn uniform_mesh_conforms_keeps_area_and_meets_the_target() {
        let f = builtin::load("cornell").unwrap().unwrap().at(0.0);
        let m = Mesh::uniform(&f, 0.3, 100_000);
        let area: f32 = m.elems.iter().map(|e| e.area).sum();
        let scene: f32 = f.areas.iter().sum();
        assert!((area - scene).abs() < 1e-4 * scene, "{area} vs {scene}");
        assert!((0..m.len()).all(|e| m.diameter(e) <= 0.3 + 1e-6));
        assert!(m.len() > 5 * 2 * 4 * 4, "{} elements", m.len());
        assert_conforming(&m);
        // The budget stops it.
        let small = Mesh::uniform(&f, 0.01, 500);
        assert!(small.len() >= 500 && small.len() < 520, "{}", small.len());
    }

    /// Cut along the Cornell box's discontinuity lines (some crossing, some ending inside a
    /// triangle) and refined, for every solver's first mesh, the mesh keeps the scene's area,
    /// has no sliver, respects the budget and conforms but for a few near-coincident vertices.
    #[test]
    fn discontinuity_cuts_stay_conforming_and_keep_area() {
        use crate::radiosity::{first_mesh, Meshing, RadiositySettings, Solver};
        let f = builtin::load("cornell").unwrap().unwrap().at(0.0);
        let tr = crate::trace::Tracer::new(&f);
        let scene: f32 = f.areas.iter().sum();
        for (solver, budget) in [(Solver::Progressive, 3000), (Solver::Stochastic, 100_000)] {
            let s = RadiositySettings {
                solver,
                meshing: Meshing::Discontinuity,
                element_size: 0.3,
                max_elements: budget,
                ..Default::default()
            };
            let (m, lines, cut) = first_mesh(&f, &tr, &s);
            assert!(lines > 50 && cut > 50, "{lines} lines, {cut} vertices");
            let area: f32 = m.elems.iter().map(|e| e.area).sum();
            assert!((area - scene).abs() < 1e-4 * scene, "{area} vs {scene}");
            // No sliver (measured: the smallest element over 1e-7).
            let tiny = m.elems.iter().filter(|e| e.area <= 1e-7).count();
            assert!(m.elems.iter().all(|e| e.area > 0.0 && e.area.is_finite()));
            assert_eq!(tiny, 0, "{tiny} slivers");
            assert!(m.len() <= budget + 8, "{} elements", m.len());
            // Conforming but where two lines cross one edge within float error of each other
            // and a vertex sits within 1e-6 of a neighbour's edge (measured: 16 edges).
            let t_vertices = (0..m.len())
                .flat_map(|e| {
                    let [a, b, c] = m.corners(e);
                    [(a, b), (b, c), (c, a)].map(move |pq| (e, pq))
                })
                .filter(|&(e, (p, q))| {
                    m.verts.iter().enumerate().any(|(vi, &x)| {
                        let d = q - p;
                        let t = (x - p).dot(d) / d.length_squared();
                        !m.elems[e].v.contains(&(vi as u32))
                            && t > 1e-4
                            && t < 1.0 - 1e-4
                            && (p + d * t - x).length() < 1e-6
                    })
                })
                .count();
            println!(
                "{solver:?}: {} elements, {tiny} slivers, {t_vertices} T-vertices",
                m.len()
            );
            assert!(t_vertices <= 20, "{t_vertices} T-vertices");
        }
    }

    #[test]
    fn adaptive_refinement_splits_where_values_jump_and_stays_conforming() {
        let f = builtin::load("cornell").unwrap().unwrap().at(0.0);
        let mut m = Mesh::uniform(&f, 0.5, 100_000);
        let n0 = m.len();
        // A step in x on the floor (y = -1): elements left of x = 0.1 are bright.
        let value: Vec<Vec3> = (0..m.len())
            .map(|e| {
                let c = m.centroid(e);
                if c.y < -0.99 && c.x < 0.1 {
                    Vec3::ONE
                } else {
                    Vec3::ZERO
                }
            })
            .collect();
        let split = m.refine_adaptive(&value, 0.5, 0.05, 100_000);
        assert!(split > 0 && m.len() > n0);
        assert_conforming(&m);
        // Splits concentrated on the floor.
        let floor_new = (n0..m.len())
            .filter(|&e| m.elems[e].normal.y > 0.99)
            .count();
        assert!(
            floor_new * 2 > m.len() - n0,
            "{floor_new} of {}",
            m.len() - n0
        );
    }

    /// Gouraud values are continuous across an edge that holds a T-vertex (one element's
    /// edge, two elements' on the other side, as hierarchical radiosity's leaves meet): both
    /// sides interpolate the same values all along it. Without the fix the T-vertex takes
    /// the small elements' mean alone (0 here, against 0.8 on the long edge). A conforming
    /// mesh keeps the plain area-weighted means.
    #[test]
    fn gouraud_values_are_continuous_across_t_vertices() {
        let f = builtin::load("cornell").unwrap().unwrap().at(0.0);
        let z = Vec3::Z;
        let p = |x: f32, y: f32| Vec3::new(x, y, 0.0);
        let m = Mesh::from_triangles(&[
            ([p(0.0, 0.0), p(2.0, 0.0), p(0.0, 2.0)], 0, z),
            ([p(0.0, 0.0), p(1.0, -1.0), p(1.0, 0.0)], 0, z),
            ([p(1.0, 0.0), p(1.0, -1.0), p(2.0, 0.0)], 0, z),
        ]);
        assert_eq!(m.len(), 3);
        let c = m.corner_values(&f, &[Vec3::ONE, Vec3::ZERO, Vec3::ZERO]);
        // Each element's Gouraud value at point x of its plane (barycentric interpolation).
        let at = |e: usize, x: Vec3| {
            let [a, b, cc] = m.corners(e);
            let area = (b - a).cross(cc - a).z;
            let w1 = (cc - b).cross(x - b).z / area;
            let w2 = (a - cc).cross(x - cc).z / area;
            c[e][0] * w1 + c[e][1] * w2 + c[e][2] * (1.0 - w1 - w2)
        };
        for k in 0..=20 {
            let x = p(k as f32 / 10.0, 0.0);
            let small = if x.x <= 1.0 { 1 } else { 2 };
            let (big, fine) = (at(0, x).x, at(small, x).x);
            assert!((big - fine).abs() < 1e-5, "at {x}: {big} against {fine}");
        }
        assert!((at(0, p(1.0, 0.0)).x - 0.8).abs() < 1e-5);
        // Conforming: the plain means.
        let u = Mesh::uniform(&f, 0.5, 100_000);
        let value: Vec<Vec3> = (0..u.len()).map(|e| Vec3::splat((e % 7) as f32)).collect();
        let around = u.vertex_elements();
        let got = u.corner_values(&f, &value);
        for (e, el) in u.elems.iter().enumerate() {
            for (j, &v) in el.v.iter().enumerate() {
                let (mut sum, mut w) = (Vec3::ZERO, 0.0);
                for &o in &around[v as usize] {
                    let eo = &u.elems[o as usize];
                    if eo.normal.dot(el.normal) > 0.99
                        && f.tri_material[eo.source as usize] == f.tri_material[el.source as usize]
                    {
                        sum += value[o as usize] * eo.area;
                        w += eo.area;
                    }
                }
                assert!((got[e][j] - sum / w).abs().max_element() < 1e-5);
            }
        }
    }

    /// `open_fractions` finds what lies under a cover in the Cornell box, checked against the
    /// covers found from the geometry: the floor under the two boxes (the small one stands on
    /// it, the large one's base lies 1 cm under it) and the ceiling behind the lamp (1 cm under
    /// it, facing down). Elements wholly under a cover are closed, elements a diameter or
    /// more away from every cover's outline open, every back-wall element too (its creases
    /// and corners included). Gouraud then leaves the covered elements out: with 1 on open
    /// elements and 0 on closed ones, every open element's corners are 1 (the area-weighted
    /// mean over all of them pulled the corners on each outline down to as little as 0.125:
    /// a dark ring around the lamp and the boxes' bases).
    #[test]
    fn covered_elements_are_found_and_left_out_of_gouraud() {
        use glam::Vec2;
        let f = builtin::load("cornell").unwrap().unwrap().at(0.0);
        // As the solvers trace: every surface double-sided (the lamp's back hides the ceiling).
        let tracer = crate::trace::Tracer::two_sided(&f);
        let mut m = Mesh::uniform(&f, 0.05, 1_000_000);
        m.open = m.open_fractions(&f, &tracer);
        let xz = |p: Vec3| Vec2::new(p.x, p.z);
        // Down-facing triangles near a plane at height y: the covers of the surface there.
        let covers = |lo: f32, hi: f32| -> Vec<[Vec2; 3]> {
            (0..f.tris.len())
                .filter(|&t| {
                    f.normals[t].y < -0.99 && f.tris[t].iter().all(|p| p.y >= lo && p.y <= hi)
                })
                .map(|t| f.tris[t].map(xz))
                .collect()
        };
        let (floor, ceiling) = (covers(-1.05, -0.999), covers(0.95, 0.999));
        assert_eq!((floor.len(), ceiling.len()), (4, 2));
        let cross = |a: Vec2, b: Vec2, p: Vec2| (b - a).perp_dot(p - a);
        let inside = |t: &[Vec2; 3], p: Vec2| {
            let s = [
                cross(t[0], t[1], p),
                cross(t[1], t[2], p),
                cross(t[2], t[0], p),
            ];
            s.iter().all(|&x| x >= 0.0) || s.iter().all(|&x| x <= 0.0)
        };
        let to_edge = |t: &[Vec2; 3], p: Vec2| {
            (0..3)
                .map(|i| {
                    let (a, b) = (t[i], t[(i + 1) % 3]);
                    let h = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
                    (p - a - (b - a) * h).length()
                })
                .fold(f32::INFINITY, f32::min)
        };
        let (mut closed, mut open) = ([0; 2], [0; 2]);
        for e in 0..m.len() {
            let el = &m.elems[e];
            let c = m.corners(e).map(xz);
            let (side, cv) = match el.normal.y {
                y if y > 0.99 && m.centroid(e).y < -0.99 => (0, &floor),
                y if y < -0.99 && m.centroid(e).y > 0.999 => (1, &ceiling),
                _ => continue,
            };
            let under = |p: Vec2| cv.iter().any(|t| inside(t, p));
            let near = |p: Vec2| cv.iter().any(|t| to_edge(t, p) < m.diameter(e));
            if c.iter().all(|&p| under(p))
                && under(xz(m.centroid(e)))
                && !c.iter().any(|&p| near(p))
            {
                assert_eq!(
                    m.open[e],
                    0.0,
                    "element {e} at {} is covered",
                    m.centroid(e)
                );
                closed[side] += 1;
            } else if !c.iter().any(|&p| under(p) || near(p)) {
                assert_eq!(m.open[e], 1.0, "element {e} at {} is open", m.centroid(e));
                open[side] += 1;
            }
        }
        println!("closed (floor, ceiling) {closed:?}, open {open:?}");
        assert!(closed[0] > 50 && closed[1] > 10, "closed {closed:?}");
        assert!(open[0] > 500 && open[1] > 500, "open {open:?}");
        for e in (0..m.len()).filter(|&e| m.elems[e].normal.z > 0.99) {
            assert_eq!(m.open[e], 1.0, "back wall element at {}", m.centroid(e));
        }
        // Gouraud: 1 on open elements, 0 on closed ones.
        let value: Vec<Vec3> = m
            .open
            .iter()
            .map(|&o| Vec3::splat((o > 0.0) as u8 as f32))
            .collect();
        let lowest = |m: &Mesh| {
            let corners = m.corner_values(&f, &value);
            (0..m.len())
                .filter(|&e| value[e].x > 0.0)
                .flat_map(|e| corners[e])
                .map(|c| c.x)
                .fold(f32::INFINITY, f32::min)
        };
        assert!((lowest(&m) - 1.0).abs() < 1e-6, "{}", lowest(&m));
        let mut all = m.clone();
        all.open.clear();
        println!(
            "lowest open corner {}, without the open shares {}",
            lowest(&m),
            lowest(&all)
        );
        assert!(
            lowest(&all) < 0.2,
            "without the open shares: {}",
            lowest(&all)
        );
    }

    /// With `smooth`, a step in the values (hierarchical radiosity's, at a coarse receiver's
    /// border) becomes a ramp over the radius: on the Cornell box's back wall, 1 left of x = 0
    /// and 0 right of it, the corners a radius or more away keep their side's value, those at
    /// the step and half a radius from it lie between (without `smooth` only the step's own
    /// corners do), and no other plane's value (5 everywhere else) mixes in.
    #[test]
    fn smoothed_gouraud_ramps_a_step_within_its_plane() {
        let f = builtin::load("cornell").unwrap().unwrap().at(0.0);
        let mut m = Mesh::uniform(&f, 0.05, 1_000_000);
        m.smooth = 0.2;
        let back = |e: usize| m.elems[e].normal.z > 0.99 && m.centroid(e).z < -0.99;
        let value: Vec<Vec3> = (0..m.len())
            .map(|e| match (back(e), m.centroid(e).x < 0.0) {
                (true, true) => Vec3::ONE,
                (true, false) => Vec3::ZERO,
                _ => Vec3::splat(5.0),
            })
            .collect();
        let corners = m.corner_values(&f, &value);
        let (mut ramp, mut kept) = (0, 0);
        for e in (0..m.len()).filter(|&e| back(e)) {
            for (j, &v) in m.elems[e].v.iter().enumerate() {
                let (x, c) = (m.verts[v as usize].x, corners[e][j].x);
                assert!((0.0..=1.0).contains(&c), "corner at x {x}: {c}");
                if x.abs() > 0.2 + 0.05 {
                    assert!(
                        (c - if x < 0.0 { 1.0 } else { 0.0 }).abs() < 1e-6,
                        "x {x}: {c}"
                    );
                    kept += 1;
                } else if x.abs() < 0.01 {
                    assert!(c > 0.3 && c < 0.7, "at the step, x {x}: {c}");
                    ramp += 1;
                } else if (0.08..0.12).contains(&x.abs()) {
                    // Half a radius from the step: on the ramp (unsmoothed: 1 or 0).
                    let side = if x < 0.0 { c } else { 1.0 - c };
                    assert!(side > 0.6 && side < 0.95, "x {x}: {c}");
                    ramp += 1;
                }
            }
        }
        assert!(ramp > 20 && kept > 1000, "{ramp} at the step, {kept} kept");
    }

    #[test]
    fn degenerate_and_empty_frames_give_no_elements() {
        let mut f = builtin::load("cornell").unwrap().unwrap().at(0.0);
        f.tris[0] = [Vec3::ZERO; 3];
        f.areas[0] = 0.0;
        f.normals[0] = Vec3::ZERO;
        let m = Mesh::uniform(&f, 0.5, 1000);
        assert!(m.elems.iter().all(|e| e.source != 0 && e.area > 0.0));
        f.tris.clear();
        f.areas.clear();
        f.normals.clear();
        f.tri_material.clear();
        let m = Mesh::uniform(&f, 0.5, 1000);
        assert!(m.is_empty());
    }
}
