//! Issue 23 item 3: glTF's `doubleSided: false` on the CPU. A single-sided surface is seen
//! only from its front: camera and shading rays pass through its back, a light path that
//! strikes its back ends there, and a node that mirrors keeps fronts in front (the Khronos
//! NegativeScaleTest case). See docs/math.md, "Single-sided surfaces".

use crate::common::quads::{load, quad_under_light, Panel, Quads};
use glam::Vec3;
use irad::trace::Tracer;
use serde_json::json;

/// The triangle a vertical ray from `from` (along `dir`) hits first: its name's node is found
/// by its height (the floor at 0, the panel at 1.5, the light at 3).
fn height_hit(t: &Tracer, f: &irad::scene::Frame, from: Vec3, dir: Vec3) -> Option<f32> {
    t.intersect(from, dir, f32::INFINITY)
        .map(|h| f.point(h.tri as usize, h.b1, h.b2).y)
}

#[test]
fn camera_rays_see_a_single_sided_panel_from_its_front_only() {
    let (above, below) = (Vec3::new(0.1, 2.5, 0.05), Vec3::new(0.1, 0.5, 0.05));
    for (panel, from_above, from_below) in [
        // Facing up: seen from above; from below the ray goes on to the light.
        (Panel::Up { double: false }, 1.5, 3.0),
        (Panel::Up { double: true }, 1.5, 1.5),
        // Facing down: from above the ray goes on to the floor.
        (Panel::Down { double: false }, 0.0, 1.5),
        (Panel::Down { double: true }, 1.5, 1.5),
    ] {
        let f = quad_under_light(panel).at(0.0);
        let t = Tracer::new(&f);
        let a = height_hit(&t, &f, above, Vec3::NEG_Y).unwrap();
        let b = height_hit(&t, &f, below, Vec3::Y).unwrap();
        assert!(
            (a - from_above).abs() < 1e-4 && (b - from_below).abs() < 1e-4,
            "{panel:?}: from above hits y = {a} (expected {from_above}), from below y = {b} (expected {from_below})"
        );
        // Shadow rays too: the floor under the panel sees the light through a panel's back.
        let floor = Vec3::new(0.1, 0.0, 0.05);
        let lamp = Vec3::new(0.1, 3.0, 0.05);
        let shadowed = t.occluded(floor, Vec3::Y, lamp, Vec3::NEG_Y);
        assert_eq!(shadowed, panel != Panel::Up { double: false }, "{panel:?}");
    }
}

/// Light arriving at a single-sided panel's back goes no further and leaves no VPL there;
/// double-sided, the panel's top takes VPLs.
#[test]
fn light_paths_end_on_a_single_sided_back() {
    let on_top = |double: bool| {
        let f = quad_under_light(Panel::Down { double }).at(0.0);
        let t = Tracer::new(&f);
        let vpls = irad::vpl::paths::trace_paths(&f, &t, 1, 0, 4000);
        let top = vpls
            .iter()
            .filter(|v| (v.position.y - 1.5).abs() < 1e-3 && v.normal.y > 0.5)
            .count();
        let under = vpls
            .iter()
            .filter(|v| {
                v.position.y.abs() < 1e-3 && v.position.x.abs() < 0.5 && v.position.z.abs() < 0.5
            })
            .count();
        (top, under)
    };
    let (single, double) = (on_top(false), on_top(true));
    println!(
        "VPLs on the panel's top and on the floor under it: single {single:?}, double {double:?}"
    );
    // The panel covers 1.44 of the light's view of the floor: many paths strike its top.
    assert!(double.0 > 200, "{double:?}");
    assert_eq!(single.0, 0, "{single:?}");
}

/// Khronos' NegativeScaleTest: a node that mirrors (negative determinant) flips the winding,
/// so a single-sided quad facing up still faces up, whichever axis is mirrored.
#[test]
fn a_mirroring_node_keeps_a_single_sided_front_in_front() {
    for scale in [
        [-1.0, 1.0, 1.0],
        [1.0, -1.0, 1.0],
        [1.0, 1.0, -1.0],
        [-1.0, -1.0, 1.0],
    ] {
        let mut q = Quads::default();
        let m = q.material(0.5, 1.0, false);
        // Facing up once the node has mirrored it: built facing down where y is mirrored.
        let (u, v) = if scale[1] < 0.0 {
            ([1., 0., 0.], [0., 0., 1.])
        } else {
            ([0., 0., 1.], [1., 0., 0.])
        };
        q.quad([0., 1., 0.], u, v, m, json!({ "scale": scale }));
        let f = load(&q.finish()).at(0.0);
        let t = Tracer::new(&f);
        let y = if scale[1] < 0.0 { -1.0 } else { 1.0 };
        let down = t.intersect(Vec3::new(0.1, y + 1.0, 0.2), Vec3::NEG_Y, 10.0);
        let up = t.intersect(Vec3::new(0.1, y - 1.0, 0.2), Vec3::Y, 10.0);
        let det = scale.iter().product::<f32>();
        let normal = f.normals[0];
        assert!(
            down.is_some() && up.is_none() && normal.y > 0.99,
            "scale {scale:?} (determinant {det}): normal {normal}, from above {down:?}, from below {up:?}"
        );
    }
}
