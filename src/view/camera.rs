//! The view's camera: an eye, the point it turns about (the target) and a field of view, in
//! the scene's own coordinates (those of `--camera`), moved by orbit, pan, dolly and fly.
//! Pure arithmetic on [`CameraSpec`]: no window, no device.

use crate::config::CameraSpec;
use crate::scene::Scene;
use glam::Vec3;

/// The steepest the eye climbs above or dips below the target (degrees from the horizon):
/// short of the pole, where the view's up direction would flip.
pub const MAX_PITCH_DEG: f32 = 89.0;

/// The camera the scene renders from at time `t`, as a spec: its eye, a target on its view
/// axis at the depth of the scene's centre (at least a tenth of the scene's size in front),
/// and its field of view.
pub fn of_scene(scene: &Scene, t: f32) -> CameraSpec {
    let frame = scene.at(t);
    let c = &frame.camera;
    let (lo, hi) = frame.bounds();
    let centre = (lo + hi) * 0.5;
    let size = (hi - lo).length().max(1e-3);
    let depth = (centre - c.position).dot(c.forward).max(0.1 * size);
    let eye = c.position - scene.shift;
    CameraSpec {
        eye,
        target: eye + c.forward * depth,
        fov_deg: c.yfov.to_degrees(),
    }
}

/// The camera's axes: forward (eye to target), right and up, with +Y the world's up.
pub fn axes(c: &CameraSpec) -> (Vec3, Vec3, Vec3) {
    let f = (c.target - c.eye).normalize_or(Vec3::NEG_Z);
    let up0 = if f.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    let r = f.cross(up0).normalize();
    (f, r, r.cross(f))
}

/// Turns the eye about the target: `yaw` degrees about the world's up (positive: the eye moves
/// to the right, the scene turns left), `pitch` degrees up (positive: the eye rises), the
/// elevation kept within [`MAX_PITCH_DEG`]. The distance to the target is kept.
pub fn orbit(c: &mut CameraSpec, yaw: f32, pitch: f32) {
    let d = c.eye - c.target;
    let dist = d.length();
    let mut az = d.x.atan2(d.z);
    let mut el = (d.y / dist).clamp(-1.0, 1.0).asin();
    az += yaw.to_radians();
    let lim = MAX_PITCH_DEG.to_radians();
    el = (el + pitch.to_radians()).clamp(-lim, lim);
    let dir = Vec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
    c.eye = c.target + dir * dist;
}

/// Slides eye and target together across the view: `dx`, `dy` in fractions of the view's
/// height at the target's depth (positive: the camera moves right, up).
pub fn pan(c: &mut CameraSpec, dx: f32, dy: f32) {
    let (_, r, u) = axes(c);
    let h = 2.0 * (c.target - c.eye).length() * (c.fov_deg.to_radians() * 0.5).tan();
    let m = (r * dx + u * dy) * h;
    c.eye += m;
    c.target += m;
}

/// Moves the eye toward the target (`steps` > 0) or away: each step a tenth of the distance,
/// never closer than a thousandth of where it started this step.
pub fn dolly(c: &mut CameraSpec, steps: f32) {
    let d = c.eye - c.target;
    let scale = 0.9f32.powf(steps).max(1e-3);
    c.eye = c.target + d * scale;
}

/// Flies eye and target together along the view's axes: `forward`, `right`, `up` in scene
/// units.
pub fn fly(c: &mut CameraSpec, forward: f32, right: f32, up: f32) {
    let (f, r, u) = axes(c);
    let m = f * forward + r * right + u * up;
    c.eye += m;
    c.target += m;
}

/// The spec with its numbers rounded to 4 decimals (what `--camera` is given back as: short,
/// and the same view to well under a pixel).
pub fn rounded(c: &CameraSpec) -> CameraSpec {
    let r = |x: f32| (x * 1e4).round() / 1e4;
    let v = |p: Vec3| Vec3::new(r(p.x), r(p.y), r(p.z));
    CameraSpec {
        eye: v(c.eye),
        target: v(c.target),
        fov_deg: r(c.fov_deg),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> CameraSpec {
        CameraSpec {
            eye: Vec3::new(0.0, 1.0, 4.0),
            target: Vec3::new(0.0, 1.0, 0.0),
            fov_deg: 40.0,
        }
    }

    #[test]
    fn orbit_turns_about_the_target_at_the_same_distance() {
        let mut c = spec();
        orbit(&mut c, 90.0, 0.0);
        assert!(
            (c.eye - Vec3::new(4.0, 1.0, 0.0)).length() < 1e-4,
            "{}",
            c.eye
        );
        orbit(&mut c, 0.0, 30.0);
        assert!(((c.eye - c.target).length() - 4.0).abs() < 1e-4);
        assert!((c.eye.y - (1.0 + 4.0 * 30f32.to_radians().sin())).abs() < 1e-4);
        // The pole is never reached.
        orbit(&mut c, 0.0, 500.0);
        let el = ((c.eye.y - c.target.y) / 4.0).asin().to_degrees();
        assert!((el - MAX_PITCH_DEG).abs() < 1e-2, "{el}");
        assert_eq!(c.target, spec().target);
    }

    #[test]
    fn pan_fly_and_dolly_move_as_documented() {
        let mut c = spec();
        pan(&mut c, 0.5, 0.0);
        let h = 2.0 * 4.0 * 20f32.to_radians().tan();
        assert!((c.eye.x - 0.5 * h).abs() < 1e-4 && (c.target.x - 0.5 * h).abs() < 1e-4);
        let mut c = spec();
        fly(&mut c, 1.0, 0.0, 0.5);
        assert!(
            (c.eye - Vec3::new(0.0, 1.5, 3.0)).length() < 1e-5,
            "{}",
            c.eye
        );
        let mut c = spec();
        dolly(&mut c, 1.0);
        assert!(((c.eye - c.target).length() - 3.6).abs() < 1e-4);
    }
}
