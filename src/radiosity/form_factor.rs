//! Form factors. The unoccluded part is exact: the form factor from a differential area at
//! `x` (normal `n`) to a polygon is Lambert's contour integral,
//!
//! `F(dA_x -> P) = 1/(2 pi) * sum_k angle(R_k, R_k+1) * n . unit(R_k x R_k+1)`, `R_k = p_k - x`,
//!
//! after clipping the polygon to the half-space above `x`'s plane. Element-to-element form
//! factors average it over fixed sample points of the receiving element, each multiplied by
//! the fraction of visibility rays (through the scene's BVH) that reach fixed points on the
//! sending element unblocked.

use super::mesh::Mesh;
use crate::trace::Tracer;
use glam::Vec3;
use std::f32::consts::PI;

/// Barycentric sample points of an element: 1 (centroid), 3 or 4 (centroid and three
/// points halfway to the corners), 6, or 7 (both rings and the centroid).
pub fn sample_points(count: usize) -> &'static [[f32; 3]] {
    const C: f32 = 1.0 / 3.0;
    const A: f32 = 2.0 / 3.0;
    const B: f32 = 1.0 / 6.0;
    const D: f32 = 0.1;
    const E: f32 = 0.45;
    const ALL: [[f32; 3]; 7] = [
        [C, C, C],
        [A, B, B],
        [B, A, B],
        [B, B, A],
        [D, E, E],
        [E, D, E],
        [E, E, D],
    ];
    const THREE: [[f32; 3]; 3] = [[A, B, B], [B, A, B], [B, B, A]];
    match count {
        0 | 1 => &ALL[..1],
        2 | 3 => &THREE,
        4 | 5 => &ALL[..4],
        _ => &ALL,
    }
}

pub fn at(c: &[Vec3; 3], b: [f32; 3]) -> Vec3 {
    c[0] * b[0] + c[1] * b[1] + c[2] * b[2]
}

/// Clips a polygon to the half-space `n . (p - x) >= 0` (Sutherland-Hodgman) into `out`,
/// returning the clipped polygon's vertex count. A polygon of `k` vertices clips to at most
/// `k + 1`; vertices past `out`'s length are dropped (polygons here have at most 4).
fn clip(poly: &[Vec3], x: Vec3, n: Vec3, out: &mut [Vec3; 8]) -> usize {
    let mut m = 0;
    let mut push = |p: Vec3| {
        if m < out.len() {
            out[m] = p;
            m += 1;
        }
    };
    let k = poly.len();
    for i in 0..k {
        let (p, q) = (poly[i], poly[(i + 1) % k]);
        let (dp, dq) = (n.dot(p - x), n.dot(q - x));
        if dp >= 0.0 {
            push(p);
        }
        if (dp >= 0.0) != (dq >= 0.0) {
            let t = dp / (dp - dq);
            push(p + (q - p) * t);
        }
    }
    m
}

/// Unoccluded form factor from a differential area at `x` with unit normal `n` to the planar
/// polygon `poly` (any winding), counting only the part of the polygon above `x`'s plane.
/// Both sides of the polygon count: callers check that `x` faces the sender's front. At most
/// 7 vertices (the clipped polygon has one more; callers pass triangles and quadrilaterals).
pub fn point_to_polygon(x: Vec3, n: Vec3, poly: &[Vec3]) -> f32 {
    debug_assert!(poly.len() <= 7, "{} vertices", poly.len());
    let mut buf = [Vec3::ZERO; 8];
    let k = clip(poly, x, n, &mut buf);
    if k < 3 {
        return 0.0;
    }
    let clipped = &buf[..k];
    let mut sum = 0.0f32;
    for i in 0..k {
        let a = clipped[i] - x;
        let b = clipped[(i + 1) % k] - x;
        let c = a.cross(b);
        let cl = c.length();
        if cl <= 1e-20 {
            continue;
        }
        let angle = cl.atan2(a.dot(b));
        sum += angle * n.dot(c) / cl;
    }
    (sum.abs() / (2.0 * PI)).min(1.0)
}

/// FormFactorAccuracy of an element-to-element estimate: receiver sample points and visibility rays
/// per point.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct FormFactorAccuracy {
    pub points: usize,
    pub rays: usize,
}

/// Form factor F(i -> j): the fraction of the energy leaving element `i` that reaches the
/// front of element `j`, with visibility through `tracer` (`None`: unoccluded). Returns 0
/// when they do not face each other.
pub fn element(
    mesh: &Mesh,
    tracer: Option<&Tracer>,
    i: usize,
    j: usize,
    q: FormFactorAccuracy,
) -> f32 {
    if i == j {
        return 0.0;
    }
    let (ci, cj) = (mesh.corners(i), mesh.corners(j));
    let (ni, nj) = (mesh.elems[i].normal, mesh.elems[j].normal);
    between(&ci, ni, &cj, nj, tracer, q).0
}

/// Whether the front sides of triangles (ci, ni) and (cj, nj) can see each other at all
/// (some corner of each lies in front of the other).
pub fn facing(ci: &[Vec3; 3], ni: Vec3, cj: &[Vec3; 3], nj: Vec3) -> bool {
    let eps = 1e-6;
    cj.iter().any(|&p| ni.dot(p - ci[0]) > eps) && ci.iter().any(|&p| nj.dot(p - cj[0]) > eps)
}

/// The share of rays from `x` (normal `ni`) to the points `targets` (barycentrics) of
/// triangle `cj` that arrive unoccluded, counting only the points above `x`'s plane (1 when
/// there are none), and the rays cast.
pub fn visibility(
    x: Vec3,
    ni: Vec3,
    cj: &[Vec3; 3],
    nj: Vec3,
    tr: &Tracer,
    targets: &[[f32; 3]],
) -> (f32, u32) {
    let (mut seen, mut tried) = (0, 0);
    for &t in targets {
        let y = at(cj, t);
        if ni.dot(y - x) > 0.0 {
            tried += 1;
            seen += u32::from(!tr.occluded(x, ni, y, nj));
        }
    }
    if tried == 0 {
        (1.0, 0)
    } else {
        (seen as f32 / tried as f32, tried)
    }
}

/// Form factor from triangle `ci` (normal `ni`) to the front of triangle `cj`, and the
/// number of visibility rays cast.
pub fn between(
    ci: &[Vec3; 3],
    ni: Vec3,
    cj: &[Vec3; 3],
    nj: Vec3,
    tracer: Option<&Tracer>,
    q: FormFactorAccuracy,
) -> (f32, u32) {
    let (f, _, rays) = between_open(ci, ni, cj, nj, tracer, q);
    (f, rays)
}

/// [`between`], and the same estimate without occlusion: (form factor, unoccluded form
/// factor, rays cast).
pub fn between_open(
    ci: &[Vec3; 3],
    ni: Vec3,
    cj: &[Vec3; 3],
    nj: Vec3,
    tracer: Option<&Tracer>,
    q: FormFactorAccuracy,
) -> (f32, f32, u32) {
    if !facing(ci, ni, cj, nj) {
        return (0.0, 0.0, 0);
    }
    let targets = sample_points(q.rays);
    let pts = sample_points(q.points);
    let (mut sum, mut open) = (0.0, 0.0);
    let mut rays = 0;
    for &b in pts {
        let x = at(ci, b);
        if nj.dot(x - cj[0]) <= 0.0 {
            continue; // behind the sender
        }
        let f = point_to_polygon(x, ni, cj);
        if f <= 0.0 {
            continue;
        }
        let vis = match tracer {
            None => 1.0,
            Some(tr) => {
                let (v, tried) = visibility(x, ni, cj, nj, tr, targets);
                rays += tried;
                v
            }
        };
        sum += f * vis;
        open += f;
    }
    let k = pts.len() as f32;
    (sum / k, open / k, rays)
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
pub(crate) mod tests {
    use super::*;
    use crate::scene::builtin;

    /// Two parallel, coaxial rectangles a x b at distance c: Howell's catalogue of
    /// configuration factors, C-11 (also Siegel and Howell, Thermal Radiation Heat Transfer,
    /// appendix C): with X = a/c, Y = b/c,
    /// F = 2/(pi X Y) [ ln sqrt((1+X^2)(1+Y^2)/(1+X^2+Y^2)) + X sqrt(1+Y^2) atan(X/sqrt(1+Y^2))
    ///   + Y sqrt(1+X^2) atan(Y/sqrt(1+X^2)) - X atan X - Y atan Y ].
    pub(crate) fn parallel_squares(a: f32, c: f32) -> f32 {
        let (x, y) = ((a / c) as f64, (a / c) as f64);
        let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
        let f = 2.0 / (std::f64::consts::PI * x * y)
            * (((1.0 + x * x) * (1.0 + y * y) / (1.0 + x * x + y * y))
                .sqrt()
                .ln()
                + x * sy * (x / sy).atan()
                + y * sx * (y / sx).atan()
                - x * x.atan()
                - y * y.atan());
        f as f32
    }

    /// Perpendicular rectangles sharing an edge of length l, widths w (sender's) and h:
    /// Howell C-14 (Siegel and Howell appendix C): with W = w/l, H = h/l, F(1 -> 2) for the
    /// rectangle of width w to the one of width h is
    /// 1/(pi W) [ W atan(1/W) + H atan(1/H) - sqrt(H^2+W^2) atan(1/sqrt(H^2+W^2))
    ///   + 1/4 ln( (1+W^2)(1+H^2)/(1+W^2+H^2) * (W^2(1+W^2+H^2)/((1+W^2)(W^2+H^2)))^(W^2)
    ///   * (H^2(1+H^2+W^2)/((1+H^2)(H^2+W^2)))^(H^2) ) ].
    fn perpendicular(l: f32, w: f32, h: f32) -> f32 {
        let (w, h) = ((w / l) as f64, (h / l) as f64);
        let (w2, h2) = (w * w, h * h);
        let r = (w2 + h2).sqrt();
        let log = ((1.0 + w2) * (1.0 + h2) / (1.0 + w2 + h2)).ln()
            + w2 * (w2 * (1.0 + w2 + h2) / ((1.0 + w2) * (w2 + h2))).ln()
            + h2 * (h2 * (1.0 + h2 + w2) / ((1.0 + h2) * (h2 + w2))).ln();
        let f = 1.0 / (std::f64::consts::PI * w)
            * (w * (1.0 / w).atan() + h * (1.0 / h).atan() - r * (1.0 / r).atan() + 0.25 * log);
        f as f32
    }

    /// A rectangle (corner, edge u, edge v) as a mesh bisected down to `size`, normal u x v.
    fn rect_mesh(corner: Vec3, u: Vec3, v: Vec3, size: f32) -> (Mesh, [Vec3; 4]) {
        let quad = [corner, corner + u, corner + u + v, corner + v];
        let mut f = builtin::load("furnace").unwrap().unwrap().at(0.0);
        f.tris = vec![[quad[0], quad[1], quad[2]], [quad[0], quad[2], quad[3]]];
        f.normals = vec![u.cross(v).normalize(); 2];
        f.areas = vec![0.5 * u.cross(v).length(); 2];
        f.tri_material = vec![0; 2];
        (Mesh::uniform(&f, size, 1 << 20), quad)
    }

    /// Area-weighted form factor from a meshed receiver to a whole polygon.
    fn mesh_to_polygon(m: &Mesh, poly: &[Vec3], points: usize) -> f32 {
        let mut sum = 0.0;
        let mut area = 0.0;
        for e in 0..m.len() {
            let c = m.corners(e);
            let pts = sample_points(points);
            let f: f32 = pts
                .iter()
                .map(|&b| point_to_polygon(at(&c, b), m.elems[e].normal, poly))
                .sum::<f32>()
                / pts.len() as f32;
            sum += f * m.elems[e].area;
            area += m.elems[e].area;
        }
        sum / area
    }

    #[test]
    fn parallel_coaxial_squares_match_the_catalogue() {
        for (a, c) in [(1.0f32, 1.0f32), (1.0, 0.5), (2.0, 3.0)] {
            // Receiver at z = 0 facing +z, sender at z = c.
            let (m, _) = rect_mesh(
                Vec3::new(-a / 2.0, -a / 2.0, 0.0),
                Vec3::X * a,
                Vec3::Y * a,
                a / 8.0,
            );
            let sender = [
                Vec3::new(-a / 2.0, -a / 2.0, c),
                Vec3::new(a / 2.0, -a / 2.0, c),
                Vec3::new(a / 2.0, a / 2.0, c),
                Vec3::new(-a / 2.0, a / 2.0, c),
            ];
            let got = mesh_to_polygon(&m, &sender, 7);
            let want = parallel_squares(a, c);
            // Measured relative errors 2e-4, 5e-4 (c = a/2), 2e-4.
            assert!(
                (got - want).abs() < 7.5e-4 * want,
                "a {a} c {c}: {got} vs {want}"
            );
        }
        // a = c: the catalogue's 0.1998.
        assert!((parallel_squares(1.0, 1.0) - 0.1998).abs() < 1e-4);
    }

    #[test]
    fn perpendicular_rectangles_sharing_an_edge_match_the_catalogue() {
        for (l, w, h) in [(1.0f32, 1.0f32, 1.0f32), (2.0, 1.0, 0.5), (1.0, 0.5, 2.0)] {
            // Sender-of-the-formula "1" lies in z = 0 (x in [0, w]) facing +z; "2" lies in
            // x = 0 (z in [0, h]) facing +x; the shared edge runs along y in [0, l].
            let (m, _) = rect_mesh(Vec3::ZERO, Vec3::X * w, Vec3::Y * l, w.min(l) / 16.0);
            let other = [
                Vec3::ZERO,
                Vec3::new(0.0, l, 0.0),
                Vec3::new(0.0, l, h),
                Vec3::new(0.0, 0.0, h),
            ];
            let got = mesh_to_polygon(&m, &other, 7);
            let want = perpendicular(l, w, h);
            // The integrand has a log singularity on the shared edge: measured relative
            // errors 2e-5, 1.3e-4, 2e-5.
            assert!(
                (got - want).abs() < 2e-4 * want,
                "l {l} w {w} h {h}: {got} vs {want}"
            );
        }
        // Unit squares: the catalogue's 0.2000.
        assert!((perpendicular(1.0, 1.0, 1.0) - 0.2000).abs() < 1e-4);
    }

    #[test]
    fn point_to_polygon_clips_and_is_zero_behind() {
        let sq = [
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(1.0, -1.0, 1.0),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(-1.0, 1.0, 1.0),
        ];
        // An infinite plane would give 1; a big square far above nearly 1.
        let big: Vec<Vec3> = sq
            .iter()
            .map(|p| Vec3::new(p.x * 1e3, p.y * 1e3, 1.0))
            .collect();
        assert!((point_to_polygon(Vec3::ZERO, Vec3::Z, &big) - 1.0).abs() < 1e-3);
        // Facing away: nothing.
        assert_eq!(point_to_polygon(Vec3::ZERO, -Vec3::Z, &sq), 0.0);
        // Looking sideways (normal +x): the half with x > 0 counts, by symmetry of the
        // clipped polygon against the full one seen from a tilted normal.
        let half = point_to_polygon(Vec3::ZERO, Vec3::X, &sq);
        assert!(half > 0.0 && half < point_to_polygon(Vec3::ZERO, Vec3::Z, &sq));
    }

    #[test]
    fn reciprocity_rows_and_closed_box() {
        // The furnace is a closed cube: every element's row sums to 1.
        let f = builtin::load("furnace").unwrap().unwrap().at(0.0);
        let tr = Tracer::new(&f);
        let m = Mesh::uniform(&f, 0.8, 10_000);
        let q = FormFactorAccuracy { points: 7, rays: 4 };
        let n = m.len();
        let ff: Vec<Vec<f32>> = (0..n)
            .map(|i| (0..n).map(|j| element(&m, Some(&tr), i, j, q)).collect())
            .collect();
        let mut worst_row = 0.0f32;
        let mut worst_recip = 0.0f32;
        let mut worst_far = 0.0f32;
        for i in 0..n {
            let row: f32 = ff[i].iter().sum();
            assert!(row <= 1.0 + 1e-3, "row {i} sums to {row}");
            worst_row = worst_row.max((row - 1.0).abs());
            for j in 0..n {
                let (a, b) = (m.elems[i].area * ff[i][j], m.elems[j].area * ff[j][i]);
                if a.max(b) > 1e-3 {
                    let r = (a - b).abs() / a.max(b);
                    worst_recip = worst_recip.max(r);
                    let apart = (m.centroid(i) - m.centroid(j)).length()
                        > 2.0 * m.diameter(i).max(m.diameter(j));
                    if apart {
                        worst_far = worst_far.max(r);
                    }
                }
            }
        }
        // Measured: rows within 3e-7 of 1 (the contour integrals of a closed cube cover the
        // hemisphere exactly); reciprocity within 0.9% for pairs more than two element sizes
        // apart, 9.5% over all pairs (7 points under-resolve neighbours across a corner).
        assert!(worst_row < 1e-5, "row error {worst_row}");
        assert!(
            worst_far < 0.0135,
            "reciprocity error, separated pairs {worst_far}"
        );
        assert!(worst_recip < 0.14, "reciprocity error {worst_recip}");
        // Occlusion: in the Cornell box the floor under the small box cannot see the light.
        let f = builtin::load("cornell").unwrap().unwrap().at(0.0);
        let tr = Tracer::new(&f);
        let m = Mesh::uniform(&f, 0.1, 100_000);
        let light = (0..m.len())
            .find(|&e| f.emission(m.elems[e].source as usize).x > 0.0)
            .unwrap();
        let under = (0..m.len())
            .find(|&e| {
                let c = m.centroid(e);
                m.elems[e].normal.y > 0.99 && (c - Vec3::new(0.335, -1.0, 0.38)).length() < 0.08
            })
            .unwrap();
        assert!(element(&m, None, under, light, q) > 0.0);
        assert_eq!(element(&m, Some(&tr), under, light, q), 0.0);
    }
}
