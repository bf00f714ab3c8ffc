//! The atrium: a Sponza-class built-in (issue 11 item 7). A 30 x 14 m court open to the sky,
//! two storeys of arcades (44 columns, 40 arches) along its long sides under gallery slabs,
//! lit by a sun: a large emitting quad high above the open roof that slides across the sky
//! over 4 s (an area light, so that its shadows are soft), and a spot light on a column of
//! the north arcade aimed at the court's floor, whose beam sweeps 20 degrees and back over
//! the same 4 s (KHR_lights_punctual). Columns and arches are one mesh each, instanced by
//! their nodes, so the file stays small while the scene has about 134k triangles. Both are
//! closed solids (columns capped, arches closed at their feet), as the stone they stand for.

use super::GltfBuilder;
use glam::{Quat, Vec3};
use serde_json::json;
use std::f32::consts::PI;

/// Column: segments around, rings up.
const COLUMN_SEGMENTS: usize = 64;
const COLUMN_RINGS: usize = 20;
/// Arch: segments along the half circle.
const ARCH_SEGMENTS: usize = 48;
/// Column spacing along x, and the number of columns per row.
const SPACING: f32 = 2.5;
const COLUMNS: usize = 11;
/// The two storeys: (floor of the storey, height where the arches spring).
const STOREYS: [(f32, f32); 2] = [(0.0, 4.5), (6.0, 10.0)];
/// The colonnades stand at z = +-ROW.
const ROW: f32 = 4.5;

/// The spot light: where it hangs (in front of the north arcade's column at x = -5, under
/// its capital), the floor point its axis meets at t = 0, its cone (inner and outer half
/// angles, degrees) and intensity (W/sr, white; written as candela, 683 per W/sr).
pub const SPOT_AT: Vec3 = Vec3::new(-5.0, 4.2, -4.0);
pub const SPOT_TARGET: Vec3 = Vec3::new(-3.0, 0.0, -1.0);
pub const SPOT_CONE_DEG: [f32; 2] = [15.0, 25.0];
pub const SPOT_INTENSITY: f32 = 240.0;
/// The beam's sweep: a turn about the vertical through the light, 0 -> 20 -> 0 degrees at
/// t = 0, 2, 4 s.
pub const SPOT_SWEEP_DEG: f32 = 20.0;

/// Pushes quad (a, b, c, d) as two triangles facing `out` (the winding is chosen to match).
fn quad_facing(idx: &mut Vec<u32>, p: &[Vec3], q: [u32; 4], out: Vec3) {
    let [a, b, c, d] = q;
    let n = (p[b as usize] - p[a as usize]).cross(p[c as usize] - p[a as usize]);
    if n.dot(out) >= 0.0 {
        idx.extend([a, b, c, a, c, d]);
    } else {
        idx.extend([a, c, b, a, d, c]);
    }
}

/// Pushes triangle (a, b, c) facing `out`.
fn tri_facing(idx: &mut Vec<u32>, p: &[Vec3], [a, b, c]: [u32; 3], out: Vec3) {
    let n = (p[b as usize] - p[a as usize]).cross(p[c as usize] - p[a as usize]);
    if n.dot(out) >= 0.0 {
        idx.extend([a, b, c]);
    } else {
        idx.extend([a, c, b]);
    }
}

/// A column of height 1 (scaled by its node): base and capital wider than the shaft, capped
/// at both ends, so that it is a closed solid (whose back faces the raster passes skip).
fn column(b: &mut GltfBuilder, material: usize) -> usize {
    let mut p = Vec::new();
    for k in 0..=COLUMN_RINGS {
        let h = k as f32 / COLUMN_RINGS as f32;
        let r = match k {
            0 | 1 => 0.4,
            k if k + 1 >= COLUMN_RINGS => 0.42,
            _ => 0.3 - 0.03 * h,
        };
        for j in 0..COLUMN_SEGMENTS {
            let a = 2.0 * PI * j as f32 / COLUMN_SEGMENTS as f32;
            p.push(Vec3::new(r * a.cos(), h, -r * a.sin()));
        }
    }
    let mut idx = Vec::new();
    let at = |k: usize, j: usize| (k * COLUMN_SEGMENTS + j % COLUMN_SEGMENTS) as u32;
    for k in 0..COLUMN_RINGS {
        for j in 0..COLUMN_SEGMENTS {
            let q = [at(k, j), at(k, j + 1), at(k + 1, j + 1), at(k + 1, j)];
            let mid = (p[q[0] as usize] + p[q[2] as usize]) * 0.5;
            quad_facing(&mut idx, &p, q, mid * Vec3::new(1.0, 0.0, 1.0));
        }
    }
    for (k, out) in [(0, -Vec3::Y), (COLUMN_RINGS, Vec3::Y)] {
        let c = p.len() as u32;
        p.push(Vec3::new(0.0, k as f32 / COLUMN_RINGS as f32, 0.0));
        for j in 0..COLUMN_SEGMENTS {
            tri_facing(&mut idx, &p, [c, at(k, j), at(k, j + 1)], out);
        }
    }
    b.mesh("column", &p, &idx, material)
}

/// A half-circle arch of centre radius 1 in the xy plane (x from 1 to -1), 0.3 wide radially
/// and 0.6 deep in z, every face facing out of the band, closed at both ends (facing down).
fn arch(b: &mut GltfBuilder, material: usize) -> usize {
    let (ri, ro, d) = (0.85, 1.15, 0.3);
    let mut p = Vec::new();
    for i in 0..=ARCH_SEGMENTS {
        let a = PI * i as f32 / ARCH_SEGMENTS as f32;
        let u = Vec3::new(a.cos(), a.sin(), 0.0);
        p.extend([
            u * ri - Vec3::Z * d,
            u * ro - Vec3::Z * d,
            u * ro + Vec3::Z * d,
            u * ri + Vec3::Z * d,
        ]);
    }
    let mut idx = Vec::new();
    for i in 0..ARCH_SEGMENTS {
        let a = PI * (i as f32 + 0.5) / ARCH_SEGMENTS as f32;
        let centre = Vec3::new(a.cos(), a.sin(), 0.0);
        for f in 0..4u32 {
            let (s, t) = (4 * i as u32, 4 * (i as u32 + 1));
            let q = [s + f, s + (f + 1) % 4, t + (f + 1) % 4, t + f];
            let mid = (p[q[0] as usize] + p[q[2] as usize]) * 0.5;
            quad_facing(&mut idx, &p, q, mid - centre);
        }
    }
    let last = 4 * ARCH_SEGMENTS as u32;
    for s in [0, last] {
        quad_facing(&mut idx, &p, [s, s + 1, s + 2, s + 3], -Vec3::Y);
    }
    b.mesh("arch", &p, &idx, material)
}

/// The court's shell: floor, four walls 14 m high, gallery floors and roofs.
fn shell(b: &mut GltfBuilder, stone: usize, floor: usize, wall: usize) -> Vec<usize> {
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let h = 7.0;
    let quads = [
        ("floor", Vec3::ZERO, z * 7.0, x * 15.0, floor),
        ("wall_north", Vec3::new(0.0, h, -7.0), x * 15.0, y * h, wall),
        ("wall_south", Vec3::new(0.0, h, 7.0), y * h, x * 15.0, wall),
        ("wall_west", Vec3::new(-15.0, h, 0.0), y * h, z * 7.0, wall),
        ("wall_east", Vec3::new(15.0, h, 0.0), z * 7.0, y * h, wall),
    ];
    let mut nodes = Vec::new();
    for (name, c, u, v, m) in quads {
        let mesh = b.quad_mesh(name, c, u, v, m);
        nodes.push(b.node(json!({ "name": name, "mesh": mesh })));
    }
    let slab = b.cube_mesh("slab", stone);
    for side in [-1.0f32, 1.0] {
        for (i, y) in [5.85, 11.35].into_iter().enumerate() {
            let name = if i == 0 { "gallery" } else { "gallery_roof" };
            nodes.push(b.node(json!({
                "name": name, "mesh": slab,
                "translation": [0.0, y, side * 5.75],
                "scale": [15.0, 0.15, 1.25],
            })));
        }
    }
    nodes
}

/// The arcades: columns under half-circle arches on both storeys of both long sides.
fn arcades(b: &mut GltfBuilder, stone: usize) -> Vec<usize> {
    let col = column(b, stone);
    let arc = arch(b, stone);
    let x0 = -(COLUMNS as f32 - 1.0) * SPACING * 0.5;
    let mut nodes = Vec::new();
    for side in [-1.0f32, 1.0] {
        for (floor, spring) in STOREYS {
            for i in 0..COLUMNS {
                let x = x0 + i as f32 * SPACING;
                nodes.push(b.node(json!({
                    "name": "column", "mesh": col,
                    "translation": [x, floor, side * ROW],
                    "scale": [1.0, spring - floor, 1.0],
                })));
                if i + 1 < COLUMNS {
                    let r = SPACING * 0.5;
                    nodes.push(b.node(json!({
                        "name": "arch", "mesh": arc,
                        "translation": [x + r, spring, side * ROW],
                        "scale": [r, r, 1.0],
                    })));
                }
            }
        }
    }
    nodes
}

/// The whole atrium, its camera at the west end looking east, and the sliding sun.
pub(super) fn atrium(b: &mut GltfBuilder) {
    let stone = b.material("stone", [0.7, 0.65, 0.55], [0.0; 3]);
    let floor = b.material("floor", [0.5, 0.45, 0.4], [0.0; 3]);
    let wall = b.material("plaster", [0.75, 0.7, 0.6], [0.0; 3]);
    let sun = b.material("sun", [0.0; 3], [40.0, 37.0, 32.0]);
    let mut roots = shell(b, stone, floor, wall);
    roots.extend(arcades(b, stone));
    let sun_mesh = b.quad_mesh("sun", Vec3::ZERO, Vec3::X * 6.0, Vec3::Z * 4.0, sun);
    let sun_node =
        b.node(json!({ "name": "sun", "mesh": sun_mesh, "translation": [-6.0, 30.0, 0.0] }));
    roots.push(sun_node);
    let aim = Quat::from_rotation_arc(Vec3::NEG_Z, (SPOT_TARGET - SPOT_AT).normalize());
    let spot = b.spot_node(
        "spot",
        SPOT_AT,
        aim,
        SPOT_INTENSITY * crate::scene::lights::LUMENS_PER_WATT,
        SPOT_CONE_DEG,
    );
    roots.push(spot);
    let look = Quat::from_rotation_y(-PI / 2.0) * Quat::from_rotation_x(8f32.to_radians());
    roots.push(b.camera_node([-13.5, 2.0, 0.0], look, 60.0));
    b.roots = roots;
    let times = [0.0, 2.0, 4.0];
    let x = [-6.0, 6.0, -6.0];
    let values: Vec<f32> = x.iter().flat_map(|&x| [x, 30.0, 0.0]).collect();
    b.animate("sun", sun_node, "translation", "LINEAR", &times, &values);
    let values: Vec<f32> = [0.0, SPOT_SWEEP_DEG, 0.0]
        .iter()
        .flat_map(|&a: &f32| (Quat::from_rotation_y(a.to_radians()) * aim).to_array())
        .collect();
    b.animate("spot", spot, "rotation", "LINEAR", &times, &values);
}
