//! Issue 23 item 5, the emissive-texture part: a triangle's mean emission (which chooses
//! emitters by power) is averaged over a lattice whose points in all are bounded, and kept
//! between frames, so a 200k-triangle model with an emissive texture loads in about a
//! second (68.9 s before: `benches/big_emissive.py`).

use crate::common::quads::{load, Quads};
use base64::Engine;
use irad::scene::Scene;
use serde_json::json;
use std::sync::Arc;

/// Emissive quads whose texture coordinates span `extents` of a 64 x 64 noise texture
/// (bilinear), over a grey floor.
fn textured_emitters(extents: &[f32]) -> Scene {
    let mut q = Quads::default();
    let grey = q.material(0.5, 0.0, true);
    let lamp = q.material(0.5, 1.0, true);
    q.quad([0.; 3], [0., 0., 4.], [4., 0., 0.], grey, json!({}));
    let mut uvs = Vec::new();
    for (k, &s) in extents.iter().enumerate() {
        let x = -3.0 + 1.2 * k as f32;
        q.quad([x, 2., 0.], [0.5, 0., 0.], [0., 0., 0.5], lamp, json!({}));
        uvs.push(q.floats(&[0., 0., s, 0., s, s, 0., s], "VEC2"));
    }
    let mut doc = q.finish();
    for (k, uv) in uvs.into_iter().enumerate() {
        doc["meshes"][k + 1]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(uv);
    }
    let mut state = 12345u32;
    let texels: Vec<u8> = (0..64 * 64)
        .flat_map(|_| {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let v = (state >> 24) as u8;
            [v, v / 2, 255 - v, 255]
        })
        .collect();
    let img = image::RgbaImage::from_raw(64, 64, texels).unwrap();
    let mut png = std::io::Cursor::new(Vec::new());
    img.write_to(&mut png, image::ImageFormat::Png).unwrap();
    let png = base64::engine::general_purpose::STANDARD.encode(png.into_inner());
    doc["materials"][lamp]["emissiveTexture"] = json!({ "index": 0 });
    doc["textures"] = json!([{ "source": 0, "sampler": 0 }]);
    doc["samplers"] = json!([{ "magFilter": 9729, "minFilter": 9729 }]);
    doc["images"] = json!([{ "uri": format!("data:image/png;base64,{png}") }]);
    load(&doc)
}

/// Scenes up to 65,536 triangles of varying emission keep the 32 x 32 lattice (the same
/// means as before); bigger ones get fewer points each, and on the small triangles such
/// meshes are made of the coarser lattice stays close to a 128 x 128 one.
#[test]
fn the_mean_emission_lattice_shrinks_only_for_big_meshes() {
    use irad::scene::lattice_side;
    assert_eq!(
        [1, 65_536, 65_537, 199_714, 10_000_000].map(lattice_side),
        [32, 32, 31, 18, 8]
    );
    let extents = [1.0 / 64.0, 1.0 / 16.0, 1.0 / 8.0, 0.25, 0.5, 1.0];
    let f = textured_emitters(&extents).at(0.0);
    // Two triangles a quad, and the back-emitting twins of the double-sided lamps.
    assert_eq!(f.emitters.tris.len(), 4 * extents.len());
    let (mut worst, mut worst_fixed) = (0.0f32, 0.0f32);
    for (k, &t) in f.emitters.tris.iter().enumerate() {
        let t = t as usize;
        // A small scene: the means the emitter list chooses by are the 32 x 32 ones.
        let listed = f.emitters.power[k] / (std::f32::consts::PI * f.areas[t]);
        let fixed = f.lattice_mean(t, 32);
        assert!((listed - fixed).abs().max_element() <= 1e-6 * fixed.max_element());
        // Triangles of a quarter texel to 32 texels, as a dense mesh's are.
        if k % extents.len() < 3 * 2 {
            let dense = irad::math::luminance(f.lattice_mean(t, 128));
            let rel = |n: u32| (irad::math::luminance(f.lattice_mean(t, n)) - dense).abs() / dense;
            worst = worst.max(rel(18));
            worst_fixed = worst_fixed.max(rel(32));
        }
    }
    println!("small triangles against 128 x 128: 18 x 18 {worst:.5}, 32 x 32 {worst_fixed:.5}");
    // Measured on this noise texture (each texel independent): 0.037 at 18 x 18 (the
    // 199,714-triangle bench's side), 0.0019 at 32 x 32. The mean only shapes how emitters
    // are chosen: sampled points carry their own radiance over the true choice probability,
    // so it costs variance, not bias.
    assert!(worst < 0.055, "worst relative difference {worst}");
}

/// The means kept between frames are those of the scene as it is: a scene whose materials
/// change gets new ones, a clone computes its own.
#[test]
fn kept_mean_emission_follows_the_materials() {
    let mut scene = textured_emitters(&[0.25, 1.0]);
    let power = |s: &Scene| s.at(0.0).emitters.total_power;
    let first = power(&scene);
    assert_eq!(power(&scene), first, "the same scene, the same means");
    let mut materials = (*scene.materials).clone();
    for m in materials
        .iter_mut()
        .filter(|m| m.emissive_texture.is_some())
    {
        m.emission *= 2.0;
    }
    scene.materials = Arc::new(materials);
    let doubled = power(&scene);
    assert!(
        (doubled - 2.0 * first).abs().max_element() < 1e-4 * first.max_element(),
        "{doubled} against 2 x {first}"
    );
    assert_eq!(power(&scene.clone()), doubled);
}

/// `Frame::keep_emitters` leaves a distribution over the kept emitters alone: each kept
/// triangle drawn in proportion to its power (luminance), none of the others ever, its index
/// in `emitter_of_tri`, and the total power theirs. Three single-sided emissive quads (no
/// back-emitting twins) of strengths 1, 2 and 4, two triangles each; the middle one dropped.
#[test]
fn kept_emitters_are_drawn_in_proportion_to_their_power_alone() {
    let mut q = Quads::default();
    let grey = q.material(0.5, 0.0, true);
    q.quad([0.; 3], [0., 0., 4.], [4., 0., 0.], grey, json!({}));
    for (k, strength) in [1.0, 2.0, 4.0].into_iter().enumerate() {
        let lamp = q.material(0.5, strength, false);
        let x = -3.0 + 1.2 * k as f32;
        q.quad([x, 2., 0.], [0.5, 0., 0.], [0., 0., 0.5], lamp, json!({}));
    }
    let mut f = load(&q.finish()).at(0.0);
    let tris = f.emitters.tris.clone();
    assert_eq!(tris.len(), 6, "two triangles a lamp");
    let (materials, tri_material) = (f.materials.clone(), f.tri_material.clone());
    let strength = |t: u32| materials[tri_material[t as usize] as usize].emission.x;
    let dropped: Vec<u32> = tris
        .iter()
        .copied()
        .filter(|&t| strength(t) == 2.0)
        .collect();
    let power = |f: &irad::scene::Frame| f.emitters.total_power.x;
    let before = power(&f);
    assert_eq!(f.keep_emitters(|t| !dropped.contains(&t)), 2);
    let em = &f.emitters;
    assert_eq!(em.tris.len(), 4);
    assert!((power(&f) - before * 5.0 / 7.0).abs() < 1e-4 * before);
    for &t in &dropped {
        assert_eq!(f.emitter_of_tri[t as usize], u32::MAX);
    }
    let mut drawn = [0usize; 2];
    let draws = 20000;
    for j in 0..draws {
        let (e, p) = em.pick((j as f32 + 0.5) / draws as f32);
        let t = em.tris[e];
        assert_eq!(f.emitter_of_tri[t as usize], e as u32);
        let s = strength(t);
        assert_ne!(s, 2.0, "a dropped emitter was drawn");
        // Each triangle of a lamp of strength s: s / (2 * (1 + 4)) of the draws.
        assert!((p - s / 10.0).abs() < 1e-5, "strength {s}: p {p}");
        drawn[(s == 4.0) as usize] += 1;
    }
    assert_eq!(drawn, [draws / 5, draws * 4 / 5]);
}
