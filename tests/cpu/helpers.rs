//! The shared helpers themselves (tests/common): what a failed image comparison leaves behind.

use crate::common;
use glam::Vec3;
use irad::image::Hdr;

fn flat(v: f32) -> Hdr {
    Hdr {
        width: 4,
        height: 2,
        data: vec![Vec3::splat(v); 8],
    }
}

/// A comparison over its bound writes the actual, expected and difference images, as EXR
/// and PNG, and names them in its message; one within its bound writes nothing.
#[test]
fn a_failed_comparison_writes_and_names_actual_expected_and_difference() {
    let (actual, expected) = (flat(0.75), flat(0.5));
    let c = common::compare("helpers", "half-off", &actual, &expected, 0.1);
    assert!((c.rel - 0.5).abs() < 1e-6, "{}", c.rel);
    let dir = common::output_dir("helpers");
    for what in ["actual", "expected", "difference"] {
        let exr = dir.join(format!("half-off-{what}.exr"));
        assert!(
            c.images.contains(&exr.display().to_string()),
            "{}",
            c.images
        );
        assert!(dir.join(format!("half-off-{what}.png")).is_file());
        let read = Hdr::read(&exr).unwrap();
        let want = match what {
            "actual" => 0.75,
            "expected" => 0.5,
            _ => 0.25,
        };
        assert!(read
            .data
            .iter()
            .all(|p| (*p - Vec3::splat(want)).abs().max_element() < 1e-3));
    }
    if !common::show_images() {
        let _ = std::fs::remove_file(dir.join("close-actual.exr"));
        let c = common::compare("helpers", "close", &flat(0.5), &expected, 0.1);
        assert!(c.rel == 0.0 && c.images.is_empty(), "{}", c.images);
        assert!(!dir.join("close-actual.exr").exists());
    }
}
