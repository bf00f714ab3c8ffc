//! Cameras: perspective cameras with a usable vertical field of view.

use super::{Ctx, LoadError};
use crate::scene::CameraDef;

pub use crate::scene::camera::FOV_RANGE;

/// A perspective camera, or None (with a warning) for an orthographic one.
pub(super) fn read(cx: &mut Ctx, c: &gltf::Camera) -> Result<Option<CameraDef>, LoadError> {
    match c.projection() {
        gltf::camera::Projection::Perspective(p) => {
            let yfov = p.yfov();
            if !(FOV_RANGE.0..=FOV_RANGE.1).contains(&yfov) {
                return Err(cx.err(format!(
                    "camera {} has a vertical field of view of {yfov} rad ({:.1} degrees); irad needs one between {} and {} rad",
                    c.index(),
                    yfov.to_degrees(),
                    FOV_RANGE.0,
                    FOV_RANGE.1
                )));
            }
            Ok(Some(CameraDef { yfov }))
        }
        gltf::camera::Projection::Orthographic(_) => {
            cx.warn("orthographic cameras are ignored");
            Ok(None)
        }
    }
}
