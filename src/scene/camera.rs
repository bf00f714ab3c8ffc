//! The pinhole camera and its pixel rays.

use glam::{Mat4, Vec2, Vec3};

/// The narrowest and widest vertical fields of view irad renders (radians): at 0 every ray is
/// the same, at pi the image plane is infinitely wide.
pub const FOV_RANGE: (f32, f32) = (1e-3, 3.1);

/// Sub-sample (i, j) of `s x s` in a pixel: its offset from the pixel's top-left corner, in
/// pixels (x right, y down). The `s^2` offsets are a rotated lattice: one in each cell of the
/// pixel's `s x s` grid and, in x and in y alike, one in each of `s^2` equal strips (n-rooks),
/// so that an edge parallel to an image axis is resolved to `1/s^2` of a pixel. `s = 1`: the
/// centre. (The G-buffer's sub-sample tiles and the CPU's edge rays sample the same offsets.)
pub fn subsample(i: u32, j: u32, s: u32) -> Vec2 {
    let (i, j, s) = (i as f32, j as f32, s as f32);
    Vec2::new((i + (j + 0.5) / s) / s, (j + (s - i - 0.5) / s) / s)
}

/// A pinhole perspective camera in world space. Image row 0 is at the top; the aspect ratio
/// is the image's (width / height), the vertical field of view is the camera's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Unit up vector, orthogonal to `forward`.
    pub up: Vec3,
    /// Unit right vector.
    pub right: Vec3,
    /// Vertical field of view in radians.
    pub yfov: f32,
}

impl Camera {
    /// From a node's world matrix (glTF cameras look down local -Z with +Y up).
    pub fn from_world(m: Mat4, yfov: f32) -> Self {
        let position = m.transform_point3(Vec3::ZERO);
        let forward = m.transform_vector3(-Vec3::Z).normalize();
        let up0 = m.transform_vector3(Vec3::Y);
        let right = forward.cross(up0).normalize();
        let up = right.cross(forward);
        Camera {
            position,
            forward,
            up,
            right,
            yfov,
        }
    }

    /// A camera at `eye` looking at `target`.
    pub fn look_at(eye: Vec3, target: Vec3, up: Vec3, yfov: f32) -> Self {
        let forward = (target - eye).normalize();
        let right = forward.cross(up).normalize();
        Camera {
            position: eye,
            forward,
            up: right.cross(forward),
            right,
            yfov,
        }
    }

    /// Whether rays can be made from it: finite, unit orthogonal axes, a field of view irad
    /// accepts (a camera scaled to zero or a field of view of 0 or pi is not).
    pub fn is_valid(&self) -> bool {
        let unit = |v: Vec3| v.is_finite() && (v.length() - 1.0).abs() < 1e-3;
        let (lo, hi) = FOV_RANGE;
        self.position.is_finite()
            && unit(self.forward)
            && unit(self.up)
            && unit(self.right)
            && self.forward.dot(self.up).abs() < 1e-3
            && (lo..=hi).contains(&self.yfov)
    }

    /// A camera that frames the bounding box from +Z.
    pub fn framing(lo: Vec3, hi: Vec3) -> Self {
        let center = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(1e-3);
        let yfov = 40f32.to_radians();
        let dist = radius / (yfov * 0.5).sin();
        Self::look_at(center + Vec3::Z * dist, center, Vec3::Y, yfov)
    }

    /// The unit direction through image position `p` in pixels (x right, y down) of a
    /// `width` x `height` image.
    pub fn ray_dir(&self, p: Vec2, width: u32, height: u32) -> Vec3 {
        let tan = (self.yfov * 0.5).tan();
        let aspect = width as f32 / height as f32;
        let sx = (2.0 * p.x / width as f32 - 1.0) * tan * aspect;
        let sy = (1.0 - 2.0 * p.y / height as f32) * tan;
        (self.forward + self.right * sx + self.up * sy).normalize()
    }

    /// The image position (pixels, x right, y down; pixel (i, j) covers [i, i+1) x [j, j+1))
    /// of direction `d` from the camera in a `width` x `height` image, the inverse of
    /// [`Camera::ray_dir`]; None for a direction not in front of the camera.
    pub fn project_dir(&self, d: Vec3, width: u32, height: u32) -> Option<Vec2> {
        let z = d.dot(self.forward);
        if z <= 1e-6 * d.length() {
            return None;
        }
        let tan = (self.yfov * 0.5).tan();
        let aspect = width as f32 / height as f32;
        let sx = d.dot(self.right) / z / (tan * aspect);
        let sy = d.dot(self.up) / z / tan;
        Some(Vec2::new(
            (sx + 1.0) * 0.5 * width as f32,
            (1.0 - sy) * 0.5 * height as f32,
        ))
    }

    /// Where point `p` falls in a `width` x `height` image ([`Camera::project_dir`]).
    pub fn project(&self, p: Vec3, width: u32, height: u32) -> Option<Vec2> {
        self.project_dir(p - self.position, width, height)
    }

    /// View matrix (world to camera, right-handed, camera looks down -Z).
    pub fn view(&self) -> Mat4 {
        Mat4::from_cols(
            self.right.extend(0.0),
            self.up.extend(0.0),
            (-self.forward).extend(0.0),
            self.position.extend(1.0),
        )
        .inverse()
    }

    /// Projection matrix for a `width` x `height` image (depth 0..1, as wgpu wants).
    pub fn projection(&self, width: u32, height: u32, near: f32, far: f32) -> Mat4 {
        let f = 1.0 / (self.yfov * 0.5).tan();
        let a = width as f32 / height as f32;
        let r = far / (near - far);
        Mat4::from_cols(
            glam::Vec4::new(f / a, 0.0, 0.0, 0.0),
            glam::Vec4::new(0.0, f, 0.0, 0.0),
            glam::Vec4::new(0.0, 0.0, r, -1.0),
            glam::Vec4::new(0.0, 0.0, r * near, 0.0),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn center_ray_is_forward_and_top_row_looks_up() {
        let c = Camera::look_at(Vec3::new(0.0, 0.0, 3.9), Vec3::ZERO, Vec3::Y, 0.686);
        let d = c.ray_dir(Vec2::new(64.0, 64.0), 128, 128);
        assert!((d - Vec3::NEG_Z).length() < 1e-6);
        assert!(c.ray_dir(Vec2::new(64.0, 0.0), 128, 128).y > 0.0);
        assert!(c.ray_dir(Vec2::new(0.0, 64.0), 128, 128).x < 0.0);
        // The top edge is half the field of view above the axis.
        let top = c.ray_dir(Vec2::new(64.0, 0.0), 128, 128);
        assert!((top.y.atan2(-top.z) - 0.343).abs() < 1e-3);
    }
}
