//! What the raster passes may leave out of a view (see docs/design.md, "What the raster
//! passes leave out"): the mesh instances wholly outside its frustum, and the back faces of
//! closed meshes ("solids": a mesh whose triangles, welded at equal positions, meet two by
//! two along every edge with opposite windings, and enclose positive volume, so that
//! counter-clockwise front faces point out). Seen from outside a solid, the nearest surface
//! along any ray is a front face, so skipping its back faces changes nothing a pass stores
//! (up to depth ties between coplanar faces); seen from inside, or cut open by the near
//! plane, it may not skip them.

use super::{Material, Primitive};
use glam::Vec3;
use std::collections::HashMap;
use std::ops::Range;

/// One mesh instance of a frame: its triangles (a run of the frame's triangle order), its
/// world-space box, and whether its mesh is closed ([`is_closed`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    pub tris: Range<u32>,
    pub lo: Vec3,
    pub hi: Vec3,
    pub closed: bool,
}

/// How a run of triangles is drawn in a view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Draw {
    /// Not at all: wholly outside the view's frustum.
    Skip,
    /// Front faces only: a solid the near plane cuts none of.
    Front,
    /// Every face.
    All,
}

/// Triangles in `runs` ([`CullView::runs`]): all of them, and those drawn front faces only.
pub fn counts(runs: &[(Range<u32>, Draw)]) -> (u64, u64) {
    runs.iter().fold((0, 0), |(all, front), (r, d)| {
        let n = r.len() as u64;
        (all + n, front + if *d == Draw::Front { n } else { 0 })
    })
}

/// A view, as the culling needs it: its near plane and side planes `(n, d)`, each with the
/// view's inside at `n.p + d >= 0`. Orthographic views have no side planes here (nothing is
/// skipped for lying beside them).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CullView {
    pub near: (Vec3, f32),
    pub sides: Vec<(Vec3, f32)>,
}

impl CullView {
    /// How an instance's triangles are drawn: skipped if its box lies wholly outside a side
    /// plane or wholly behind the near plane; front faces only if it is closed and wholly in
    /// front of the near plane; else all.
    pub fn draw(&self, i: &Instance) -> Draw {
        let (c, h) = ((i.lo + i.hi) * 0.5, (i.hi - i.lo) * 0.5);
        // The box's range of n.p + d, with a margin of a millionth of its size (so that a
        // box whose side only touches a plane counts as meeting it).
        let range = |(n, d): (Vec3, f32)| {
            let (mid, half) = (n.dot(c) + d, n.abs().dot(h));
            let tol = 1e-6 * n.length() * (c.length() + h.length());
            (mid - half - tol, mid + half + tol)
        };
        let (lo, hi) = range(self.near);
        if hi < 0.0 || self.sides.iter().any(|&p| range(p).1 < 0.0) {
            Draw::Skip
        } else if i.closed && lo > 0.0 {
            Draw::Front
        } else {
            Draw::All
        }
    }

    /// The frame's triangles `0..count` in runs, each drawn as [`CullView::draw`] says for the
    /// instance it belongs to (triangles of no instance: all), adjacent runs alike merged and
    /// skipped ones left out.
    pub fn runs(&self, instances: &[Instance], count: u32) -> Vec<(Range<u32>, Draw)> {
        let mut runs: Vec<(Range<u32>, Draw)> = Vec::new();
        let mut push = |r: Range<u32>, d: Draw| push_run(&mut runs, r, d);
        let mut at = 0;
        for i in instances {
            let r = i.tris.start.clamp(at, count)..i.tris.end.clamp(at, count);
            push(at..r.start, Draw::All);
            push(r.clone(), self.draw(i));
            at = at.max(r.end);
        }
        push(at..count, Draw::All);
        runs.retain(|(_, d)| *d != Draw::Skip);
        runs
    }
    /// Like [`CullView::runs`], over `clusters`' drawing order: a cluster is skipped where its
    /// own box or its instance's is wholly outside the view, and otherwise drawn as its
    /// instance is ([`CullView::draw`]); positions outside every cluster are drawn whole.
    pub fn cluster_runs(
        &self,
        instances: &[Instance],
        clusters: &Clusters,
        count: u32,
    ) -> Vec<(Range<u32>, Draw)> {
        let mut runs: Vec<(Range<u32>, Draw)> = Vec::new();
        let mut push = |r: Range<u32>, d: Draw| push_run(&mut runs, r, d);
        let mut at = 0;
        let mut last: Option<(usize, Draw)> = None;
        for (c, k) in &clusters.list {
            let r = c.tris.start.clamp(at, count)..c.tris.end.clamp(at, count);
            push(at..r.start, Draw::All);
            let whole = match last {
                Some((i, d)) if i == *k => d,
                _ => instances.get(*k).map_or(Draw::All, |i| self.draw(i)),
            };
            last = Some((*k, whole));
            let d = if whole != Draw::Skip && self.draw(c) == Draw::Skip {
                Draw::Skip
            } else {
                whole
            };
            push(r.clone(), d);
            at = at.max(r.end);
        }
        push(at..count, Draw::All);
        runs.retain(|(_, d)| *d != Draw::Skip);
        runs
    }
}

/// Spatial clusters of the frame's triangles, for culling views finer than by instance (see
/// docs/design.md, "Big meshes"): an instance of more than `2 size` triangles is cut into
/// runs of `size` triangles in the Morton order of their centroids within its box, each with
/// its own box; a smaller instance is one cluster. The order is a drawing order (position `k`
/// draws the frame's triangle `order[k]`) that keeps each instance's triangles together and
/// every triangle outside an instance where it was.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Clusters {
    /// The drawing order: the frame's triangle index at each position.
    pub order: Vec<u32>,
    /// Each cluster (its positions in `order` as `tris`, its box; `closed` unused) and the
    /// instance it belongs to.
    pub list: Vec<(Instance, usize)>,
}

impl Clusters {
    /// The clusters of `tris` over `instances`, of `size` triangles at most.
    pub fn of(tris: &[[Vec3; 3]], instances: &[Instance], size: usize) -> Clusters {
        let size = size.max(1);
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let mut list = Vec::new();
        for (k, i) in instances.iter().enumerate() {
            let r = i.tris.start as usize..(i.tris.end as usize).min(tris.len());
            if r.is_empty() {
                continue;
            }
            if r.len() > 2 * size {
                let ext = (i.hi - i.lo).max(Vec3::splat(1e-30));
                let code = |t: u32| {
                    let [a, b, c] = tris[t as usize];
                    let q = (((a + b + c) / 3.0 - i.lo) / ext * 1023.0)
                        .clamp(Vec3::ZERO, Vec3::splat(1023.0));
                    morton(q.x as u32) | morton(q.y as u32) << 1 | morton(q.z as u32) << 2
                };
                order[r.clone()].sort_by_cached_key(|&t| (code(t), t));
            }
            let n = if r.len() > 2 * size { size } else { r.len() };
            for s in r.clone().step_by(n) {
                let e = (s + n).min(r.end);
                list.push((
                    Instance {
                        tris: s as u32..e as u32,
                        lo: Vec3::ZERO,
                        hi: Vec3::ZERO,
                        closed: false,
                    },
                    k,
                ));
            }
        }
        let mut c = Clusters { order, list };
        c.refit(tris);
        c
    }

    /// Moves each cluster's box to `tris` (the same triangles, moved).
    pub fn refit(&mut self, tris: &[[Vec3; 3]]) {
        for (c, _) in &mut self.list {
            let ids = &self.order[c.tris.start as usize..c.tris.end as usize];
            (c.lo, c.hi) = super::bounds(ids.iter().flat_map(|&t| tris[t as usize]));
        }
    }
}

/// The bits of `v` (10 of them) spread to every third bit.
fn morton(v: u32) -> u32 {
    let mut x = v & 0x3ff;
    x = (x | x << 16) & 0x0300_00ff;
    x = (x | x << 8) & 0x0300_f00f;
    x = (x | x << 4) & 0x030c_30c3;
    (x | x << 2) & 0x0924_9249
}

/// Whether the mesh made of `prims` is closed (see the module's text), each of its separate
/// pieces enclosing positive volume. A material with an alpha cut-out opens holes in it, so a
/// mesh with one is not; nor is one with a degenerate corner (an index out of range) or a
/// corner that is not a finite number. (A hollow solid, whose inner surface faces in, is not
/// either: culling leaves it whole.)
pub fn is_closed(prims: &[Primitive], materials: &[Material]) -> bool {
    let key = |p: Vec3| p.to_array().map(f32::to_bits);
    let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
    // Directed edge (a, b) -> how many triangles run along it.
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    // The pieces (corners joined by triangles), and each triangle's first corner and share of
    // its piece's volume.
    let mut parent: Vec<u32> = Vec::new();
    let mut volumes: Vec<(u32, f64)> = Vec::new();
    for prim in prims {
        let cut = materials
            .get(prim.material)
            .is_none_or(|m| m.alpha_cutoff.is_some());
        if cut {
            return false;
        }
        for t in prim.indices.chunks_exact(3) {
            let Some(p) = t
                .iter()
                .map(|&i| prim.positions.get(i as usize).copied())
                .collect::<Option<Vec<Vec3>>>()
            else {
                return false;
            };
            if !p.iter().all(|v| v.is_finite()) {
                return false;
            }
            let mut v = [0u32; 3];
            for (k, &q) in p.iter().enumerate() {
                let n = ids.len() as u32;
                v[k] = *ids.entry(key(q)).or_insert(n);
                if v[k] == parent.len() as u32 {
                    parent.push(v[k]);
                }
            }
            let (r0, r1, r2) = (
                find(&mut parent, v[0]),
                find(&mut parent, v[1]),
                find(&mut parent, v[2]),
            );
            parent[r1 as usize] = r0;
            parent[r2 as usize] = r0;
            if v[0] == v[1] || v[1] == v[2] || v[2] == v[0] {
                return false;
            }
            for k in 0..3 {
                *edges.entry((v[k], v[(k + 1) % 3])).or_default() += 1;
            }
            let [a, b, c] = [p[0], p[1], p[2]].map(|q| q.as_dvec3());
            volumes.push((v[0], a.dot(b.cross(c)) / 6.0));
        }
    }
    let paired = edges
        .iter()
        .all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1));
    // Each piece must enclose positive volume: a mesh of an outward cube and an inside-out
    // one beside it pairs every edge and sums to a positive volume, yet the second turns its
    // back faces to the eye.
    let mut piece: HashMap<u32, f64> = HashMap::new();
    for &(v, vol) in &volumes {
        *piece.entry(find(&mut parent, v)).or_default() += vol;
    }
    !volumes.is_empty() && paired && piece.values().all(|&v| v > 0.0)
}

/// The root of `v`'s piece, halving the path on the way.
fn find(parent: &mut [u32], mut v: u32) -> u32 {
    while parent[v as usize] != v {
        let up = parent[parent[v as usize] as usize];
        parent[v as usize] = up;
        v = up;
    }
    v
}

/// Appends run `r` drawn as `d` to `runs`, merged into the last one when it is drawn alike
/// and ends where `r` starts (an empty `r` adds nothing).
fn push_run(runs: &mut Vec<(Range<u32>, Draw)>, r: Range<u32>, d: Draw) {
    if r.is_empty() {
        return;
    }
    match runs.last_mut() {
        Some((last, e)) if *e == d && last.end == r.start => last.end = r.end,
        _ => runs.push((r, d)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube's twelve triangles, counter-clockwise seen from outside.
    fn cube() -> Primitive {
        let positions = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect();
        #[rustfmt::skip]
        let indices = vec![
            0, 2, 1, 1, 2, 3, // z = 0, facing -z
            4, 5, 6, 5, 7, 6, // z = 1
            0, 1, 4, 1, 5, 4, // y = 0
            2, 6, 3, 3, 6, 7, // y = 1
            0, 4, 2, 2, 4, 6, // x = 0
            1, 3, 5, 3, 7, 5, // x = 1
        ];
        Primitive {
            positions,
            indices,
            ..Default::default()
        }
    }

    #[test]
    fn a_cube_is_closed_and_a_cube_opened_or_turned_inside_out_is_not() {
        let m = vec![Material::default()];
        let c = cube();
        // Every face points out: its normal is along the vector from the centre to it.
        for t in c.indices.chunks_exact(3) {
            let [a, b, d] = [0, 1, 2].map(|k| c.positions[t[k] as usize]);
            let n = (b - a).cross(d - a);
            assert!(n.dot((a + b + d) / 3.0 - Vec3::splat(0.5)) > 0.0, "{t:?}");
        }
        assert!(is_closed(std::slice::from_ref(&c), &m));
        // Split into two primitives with their own copies of the corners: still closed.
        let (half0, half1) = c.indices.split_at(18);
        let part = |idx: &[u32]| Primitive {
            positions: idx.iter().map(|&i| c.positions[i as usize]).collect(),
            indices: (0..idx.len() as u32).collect(),
            ..Default::default()
        };
        assert!(is_closed(&[part(half0), part(half1)], &m));
        // One face missing: open.
        let mut open = c.clone();
        open.indices.truncate(30);
        assert!(!is_closed(&[open], &m));
        // Inside out: closed but the volume is negative.
        let mut inv = c.clone();
        for t in inv.indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
        assert!(!is_closed(std::slice::from_ref(&inv), &m));
        // One triangle flipped: its edges run the same way as its neighbours'.
        let mut flip = c.clone();
        flip.indices.swap(1, 2);
        assert!(!is_closed(&[flip], &m));
        // Two cubes apart, both facing out: closed; one of them inside out (the volumes
        // still summing to a positive one): not.
        let moved = |c: &Primitive, by: Vec3, scale: f32| Primitive {
            positions: c.positions.iter().map(|&p| p * scale + by).collect(),
            ..c.clone()
        };
        let two = |b: &Primitive| {
            let mut m = c.clone();
            let base = m.positions.len() as u32;
            m.positions.extend_from_slice(&b.positions);
            m.indices.extend(b.indices.iter().map(|&i| i + base));
            m
        };
        assert!(is_closed(&[two(&moved(&c, Vec3::X * 3.0, 0.5))], &m));
        assert!(!is_closed(&[two(&moved(&inv, Vec3::X * 3.0, 0.5))], &m));
        // A doubled face: each of its edges is used by three triangles.
        let mut twice = c.clone();
        twice.indices.extend_from_slice(&[0, 2, 1]);
        assert!(!is_closed(&[twice], &m));
        // A cut-out material opens it.
        let cutout = vec![Material {
            alpha_cutoff: Some(0.5),
            ..Default::default()
        }];
        assert!(!is_closed(std::slice::from_ref(&c), &cutout));
        assert!(!is_closed(&[], &m));
    }

    #[test]
    fn runs_skip_what_lies_outside_and_back_faces_the_near_plane_does_not_cut() {
        let inst = |a: u32, b: u32, lo: f32, hi: f32, closed: bool| Instance {
            tris: a..b,
            lo: Vec3::splat(lo),
            hi: Vec3::splat(hi),
            closed,
        };
        let all = [
            inst(2, 5, 0.0, 1.0, true),
            inst(5, 9, 3.0, 4.0, true),
            inst(9, 11, 3.0, 4.0, false),
            inst(12, 14, 0.0, 1.0, true),
        ];
        let view = |near: (Vec3, f32)| CullView {
            near,
            sides: vec![],
        };
        use Draw::*;
        // The near plane x = 10 facing -x, and x = -1 facing +x: every box wholly in front.
        for near in [(-Vec3::X, 10.0), (Vec3::X, 1.0)] {
            assert_eq!(
                view(near).runs(&all, 16),
                vec![
                    (0..2, All),
                    (2..9, Front),
                    (9..12, All),
                    (12..14, Front),
                    (14..16, All)
                ]
            );
        }
        // The plane x = 3.5 through the second box, and a tilted one just inside its corner
        // (the box spans 9..12 in x + y + z): that solid is drawn whole; the boxes behind the
        // plane are skipped.
        for near in [(Vec3::X, -3.5), (Vec3::ONE, -9.001)] {
            assert_eq!(
                view(near).runs(&all, 16),
                vec![(0..2, All), (5..12, All), (14..16, All)]
            );
        }
        assert_eq!(view((Vec3::ONE, -8.999)).runs(&all, 16)[1], (5..9, Front));
        // A side plane x <= 2 leaves out the boxes at 3..4.
        let side = CullView {
            near: (Vec3::X, 1.0),
            sides: vec![(-Vec3::X, 2.0)],
        };
        assert_eq!(
            side.runs(&all, 16),
            vec![
                (0..2, All),
                (2..5, Front),
                (11..12, All),
                (12..14, Front),
                (14..16, All)
            ]
        );
        // A box touching a plane counts as meeting it: drawn whole where it touches the near
        // plane, drawn where it touches a side plane from outside.
        let touch = CullView {
            near: (Vec3::X, 0.0),
            sides: vec![(-Vec3::X, 3.0)],
        };
        assert_eq!(touch.draw(&all[0]), All);
        assert_eq!(touch.draw(&all[1]), Front);
        assert_eq!(view((Vec3::X, 1.0)).runs(&[], 3), vec![(0..3, All)]);
        assert_eq!(view((Vec3::X, 1.0)).runs(&all, 0), vec![]);
    }

    /// A 64 x 64 grid of 8192 triangles in rows (one instance, as a tessellated plane comes),
    /// a closed 12-triangle box after it and two loose triangles: the clusters cut the grid
    /// (not the box), hold every triangle once with its instance's, box what they hold, and a
    /// view draws every triangle that reaches into it, of the grid only about what it sees.
    #[test]
    fn clusters_cull_a_big_grid_by_parts_and_keep_every_triangle_seen() {
        let mut tris = Vec::new();
        for j in 0..64 {
            for i in 0..64 {
                let p = |a: f32, b: f32| Vec3::new(i as f32 + a, 0.0, j as f32 + b);
                tris.push([p(0., 0.), p(1., 0.), p(1., 1.)]);
                tris.push([p(0., 0.), p(1., 1.), p(0., 1.)]);
            }
        }
        let grid = Instance {
            tris: 0..8192,
            lo: Vec3::ZERO,
            hi: Vec3::new(64.0, 0.0, 64.0),
            closed: false,
        };
        let b = |k: u32| Vec3::new(100.0 + (k & 1) as f32, (k >> 1 & 1) as f32, (k >> 2) as f32);
        for k in 0..12 {
            tris.push([b(k % 8), b((k + 1) % 8), b((k + 3) % 8)]);
        }
        let cube = Instance {
            tris: 8192..8204,
            lo: b(0),
            hi: b(7),
            closed: true,
        };
        tris.push([Vec3::ZERO, Vec3::X, Vec3::Y]);
        tris.push([Vec3::ZERO, Vec3::Y, Vec3::Z]);
        let instances = [grid, cube];
        let c = Clusters::of(&tris, &instances, 256);
        assert_eq!(c.list.len(), 32 + 1);
        let mut seen = c.order.clone();
        seen.sort();
        assert_eq!(seen, (0..8206).collect::<Vec<u32>>());
        assert!(c.order[..8192].iter().all(|&t| t < 8192));
        assert_eq!(&c.order[8192..], &(8192..8206).collect::<Vec<u32>>()[..]);
        for (cl, k) in &c.list {
            for &t in &c.order[cl.tris.start as usize..cl.tris.end as usize] {
                assert!(instances[*k].tris.contains(&t));
                for p in tris[t as usize] {
                    assert!(p.cmpge(cl.lo).all() && p.cmple(cl.hi).all());
                }
            }
        }
        // In Morton order a cluster of 256 triangles is an 8 x 16 patch.
        let (cl, _) = &c.list[5];
        assert_eq!(((cl.hi - cl.lo).x * (cl.hi - cl.lo).z) as u32, 128);
        // A view of x <= 10 (everything in front of its near plane): the clusters that reach
        // there, the box as its instance says (front faces), the loose triangles whole.
        let view = CullView {
            near: (Vec3::Y, 1.0),
            sides: vec![(-Vec3::X, 10.0)],
        };
        let runs = view.cluster_runs(&instances, &c, 8206);
        let (all, _) = counts(&runs);
        let drawn: std::collections::HashSet<u32> = runs
            .iter()
            .flat_map(|(r, _)| c.order[r.start as usize..r.end as usize].iter().copied())
            .collect();
        for (t, tri) in tris.iter().enumerate().take(8192) {
            if tri.iter().any(|p| p.x <= 10.0) {
                assert!(drawn.contains(&(t as u32)), "triangle {t}");
            }
        }
        // The patches that reach x = 10 are those of columns 0..16: 2 x 16 x 64 = 2048
        // triangles drawn (1408 in the 11 columns seen), of the grid's 8192.
        assert_eq!(all, 2048 + 2, "{runs:?}");
        assert_eq!(runs.last(), Some(&(8204..8206, Draw::All)));
        // The plain runs draw the whole grid.
        assert_eq!(counts(&view.runs(&instances, 8206)).0, 8192 + 2);
    }
}
