//! Textures and vertex colours (issue 11 item 2) on small glTF files written here: texel
//! values against the sRGB formula written out by hand, samplers and KHR_texture_transform,
//! COLOR_0, emissive textures (emitter power and the reference's radiance), alpha MASK
//! cut-outs (rays and VPLs pass through), a missing image, and the GPU against its CPU twin.

use crate::common;
use base64::Engine;
use glam::{Vec2, Vec3};
use irad::scene::{load::load_slice, Scene};
use irad::trace::Tracer;
use serde_json::{json, Value};

/// Where this file's tests write images (`target/tmp/test-output/textures`).
const TEST: &str = "textures";

/// sRGB code to linear, written out from IEC 61966-2-1 (not the library's function).
fn lin(code: u8) -> f32 {
    let c = code as f64 / 255.0;
    (if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }) as f32
}

/// A PNG of `w x h` RGBA texels (row 0 at the top).
fn png(w: u32, h: u32, texels: &[[u8; 4]]) -> Vec<u8> {
    let img = image::RgbaImage::from_raw(w, h, texels.concat()).unwrap();
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// One embedded buffer with accessors and image views.
#[derive(Default)]
struct Gltf {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Gltf {
    fn view(&mut self, bytes: &[u8]) -> usize {
        crate::common::gltf::view(&mut self.bin, &mut self.views, bytes)
    }
    fn accessor(&mut self, bytes: &[u8], count: usize, ty: &str, component: u32) -> usize {
        let (b, v, a) = (&mut self.bin, &mut self.views, &mut self.accessors);
        crate::common::gltf::accessor(b, v, a, (bytes, count, ty, component))
    }
    /// A quad: corners (counter-clockwise seen from its front), their UVs, optional COLOR_0
    /// (u8, normalized), with `material`.
    fn quad(
        &mut self,
        p: [[f32; 3]; 4],
        uv: [[f32; 2]; 4],
        colors: Option<[[u8; 4]; 4]>,
        material: usize,
    ) -> Value {
        let (b, v, a) = (&mut self.bin, &mut self.views, &mut self.accessors);
        let pos = crate::common::gltf::positions(b, v, a, &p);
        let tc = self.accessor(bytemuck::cast_slice(uv.as_flattened()), 4, "VEC2", 5126);
        let ind = self.accessor(
            bytemuck::cast_slice(&[0u32, 1, 2, 0, 2, 3]),
            6,
            "SCALAR",
            5125,
        );
        let mut attrs = json!({ "POSITION": pos, "TEXCOORD_0": tc });
        if let Some(c) = colors {
            let acc = self.accessor(c.as_flattened(), 4, "VEC4", 5121);
            self.accessors[acc]["normalized"] = json!(true);
            attrs["COLOR_0"] = json!(acc);
        }
        json!({ "primitives": [{ "attributes": attrs, "indices": ind, "material": material }] })
    }
    fn image(&mut self, png: &[u8]) -> Value {
        let v = self.view(png);
        json!({ "bufferView": v, "mimeType": "image/png" })
    }
    fn finish(self, mut doc: Value) -> Value {
        doc["asset"] = json!({ "version": "2.0" });
        doc["accessors"] = json!(self.accessors);
        doc["bufferViews"] = json!(self.views);
        doc["buffers"] = json!([{
            "byteLength": self.bin.len(),
            "uri": format!("data:application/octet-stream;base64,{}",
                base64::engine::general_purpose::STANDARD.encode(&self.bin)),
        }]);
        doc
    }
}

fn load(doc: &Value) -> Scene {
    load_slice(doc.to_string().as_bytes(), "test.gltf", "test", None).unwrap()
}

/// A floor quad of half-width 1 at y = 0 facing +y, UVs (0,0) at (-1, -1) to (1,1) at (1, 1)
/// (u along x, v along z).
const FLOOR: [[f32; 3]; 4] = [[-1., 0., -1.], [-1., 0., 1.], [1., 0., 1.], [1., 0., -1.]];
const FLOOR_UV: [[f32; 2]; 4] = [[0., 0.], [0., 1.], [1., 1.], [1., 0.]];

/// The 2 x 2 checker of the tests: texel (i, j) codes.
const CHECKER: [[u8; 4]; 4] = [
    [200, 50, 20, 255],
    [10, 120, 240, 255],
    [255, 255, 255, 0],
    [90, 180, 60, 128],
];

/// The floor's triangle and barycentrics at world point (x, 0, z).
fn at(f: &irad::scene::Frame, x: f32, z: f32) -> (usize, f32, f32) {
    let tr = Tracer::new(f);
    let h = tr
        .intersect(Vec3::new(x, 1.0, z), Vec3::NEG_Y, f32::INFINITY)
        .expect("the floor is there");
    (h.tri as usize, h.b1, h.b2)
}

fn checker_scene(sampler: Value, transform: Option<Value>, factor: [f32; 4]) -> Scene {
    let mut g = Gltf::default();
    let floor = g.quad(FLOOR, FLOOR_UV, None, 0);
    let img = g.image(&png(2, 2, &CHECKER));
    let mut tex = json!({ "index": 0 });
    if let Some(t) = transform {
        tex["extensions"] = json!({ "KHR_texture_transform": t });
    }
    let doc = json!({
        "scene": 0, "scenes": [{ "nodes": [0, 1] }],
        "nodes": [{ "mesh": 0 }, { "mesh": 1, "translation": [0.0, 3.0, 0.0], "rotation": [1.0, 0.0, 0.0, 0.0] }],
        "meshes": [floor, g.quad(FLOOR, FLOOR_UV, None, 1)],
        "materials": [
            { "pbrMetallicRoughness": { "baseColorFactor": factor, "baseColorTexture": tex, "metallicFactor": 0.0 } },
            { "emissiveFactor": [1.0, 1.0, 1.0] },
        ],
        "textures": [{ "source": 0, "sampler": 0 }],
        "images": [img],
        "samplers": [sampler],
        "extensionsUsed": ["KHR_texture_transform"],
    });
    load(&g.finish(doc))
}

#[test]
fn a_textured_quad_reads_its_texels_times_the_factor() {
    let s = checker_scene(json!({ "magFilter": 9728 }), None, [0.8, 0.8, 0.8, 1.0]);
    let f = s.at(0.0);
    // Texel (i, j) covers u in [i/2, (i+1)/2), v in [j/2, (j+1)/2): world x = 2u - 1, z = 2v - 1.
    for (k, code) in CHECKER.iter().enumerate() {
        let (i, j) = (k % 2, k / 2);
        let (x, z) = (i as f32 - 0.5, j as f32 - 0.5);
        let (tri, b1, b2) = at(&f, x, z);
        let got = f.albedo_at(tri, b1, b2);
        let want = Vec3::new(lin(code[0]), lin(code[1]), lin(code[2])) * 0.8;
        assert!(
            (got - want).abs().max_element() < 1e-5,
            "texel {k}: {got} vs {want}"
        );
    }
    // The material's factor alone is what `albedo` (the mean-free factor) reports.
    assert_eq!(f.albedo(0), Vec3::splat(0.8));
}

#[test]
fn linear_filter_wrap_and_texture_transform_are_read() {
    // LINEAR, CLAMP_TO_EDGE in s, MIRRORED_REPEAT in t; the transform scales uv by 2: the
    // floor point (x, z) reads the texture at (u, v) = (x + 1, z + 1).
    let s = checker_scene(
        json!({ "magFilter": 9729, "wrapS": 33071, "wrapT": 33648 }),
        Some(json!({ "scale": [2.0, 2.0] })),
        [1.0, 1.0, 1.0, 1.0],
    );
    let f = s.at(0.0);
    // World (0.5, z = -0.75): u = 1.5 (clamped: the last column, i = 1), v = 0.25: texel
    // centres are at v = 0.25 (j = 0) and 0.75 -> exactly row 0: texel (1, 0).
    let (tri, b1, b2) = at(&f, 0.5, -0.75);
    let got = f.albedo_at(tri, b1, b2).x;
    assert!((got - lin(10)).abs() < 1e-4, "{got} vs {}", lin(10));
    // World (-0.75, z = 0.5): u = 0.25 (column 0), v = 1.5: mirrored, texel row index
    // floor(1.5 * 2 - 0.5) = 2 -> 2n - 1 - 2 = 1 and its neighbour 3 -> 0: halfway between
    // rows 1 and 0 of column 0 (codes 255 and 200).
    let (tri, b1, b2) = at(&f, -0.75, 0.5);
    let got = f.albedo_at(tri, b1, b2).x;
    let want = 0.5 * (lin(255) + lin(200));
    assert!((got - want).abs() < 1e-4, "{got} vs {want}");
}

#[test]
fn vertex_colours_multiply_the_base_colour() {
    let mut g = Gltf::default();
    let c = [
        [255, 0, 0, 255],
        [0, 255, 0, 255],
        [0, 0, 255, 255],
        [255, 255, 255, 255],
    ];
    let floor = g.quad(FLOOR, FLOOR_UV, Some(c), 0);
    let doc = json!({
        "scene": 0, "scenes": [{ "nodes": [0, 1] }],
        "nodes": [{ "mesh": 0 }, { "mesh": 1, "translation": [0.0, 3.0, 0.0], "rotation": [1.0, 0.0, 0.0, 0.0] }],
        "meshes": [floor, g.quad(FLOOR, FLOOR_UV, None, 1)],
        "materials": [
            { "pbrMetallicRoughness": { "baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0 } },
            { "emissiveFactor": [1.0, 1.0, 1.0] },
        ],
    });
    let s = load(&g.finish(doc));
    assert!(
        !s.warnings.iter().any(|w| w.contains("vertex colours")),
        "{:?}",
        s.warnings
    );
    let f = s.at(0.0);
    // Near corner 0 (-1, -1): red x 0.5; at the centre: the mean of corners 0 and 2 on the
    // diagonal: (0.5, 0, 0.5) x 0.5.
    let (tri, b1, b2) = at(&f, -0.999, -0.999);
    let near0 = f.albedo_at(tri, b1, b2);
    assert!(
        (near0 - Vec3::new(0.5, 0.0, 0.0)).abs().max_element() < 2e-3,
        "{near0}"
    );
    let (tri, b1, b2) = at(&f, 0.0, 0.0);
    let mid = f.albedo_at(tri, b1, b2);
    assert!(
        (mid - Vec3::new(0.25, 0.0, 0.25)).abs().max_element() < 1e-4,
        "{mid}"
    );
}

/// A 2 x 1 emissive texture: white on the left half (u < 0.5), black on the right.
fn emissive_scene(textured: bool) -> Scene {
    let mut g = Gltf::default();
    let floor = g.quad(FLOOR, FLOOR_UV, None, 0);
    let img = g.image(&png(2, 1, &[[255, 255, 255, 255], [0, 0, 0, 255]]));
    // Black: the reference's path ends at the emitter (only its emission is seen).
    let mut emitter = json!({ "emissiveFactor": [1.0, 0.5, 0.25],
        "pbrMetallicRoughness": { "baseColorFactor": [0.0, 0.0, 0.0, 1.0] } });
    if textured {
        emitter["emissiveTexture"] = json!({ "index": 0 });
    }
    let doc = json!({
        "scene": 0, "scenes": [{ "nodes": [0, 1] }],
        "nodes": [{ "mesh": 0 }, { "mesh": 1, "translation": [0.0, 3.0, 0.0], "rotation": [1.0, 0.0, 0.0, 0.0] }],
        "meshes": [floor, g.quad(FLOOR, FLOOR_UV, None, 1)],
        "materials": [
            { "pbrMetallicRoughness": { "baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0 } },
            emitter,
        ],
        "textures": [{ "source": 0, "sampler": 0 }],
        "images": [img],
        "samplers": [{ "magFilter": 9728 }],
    });
    load(&g.finish(doc))
}

#[test]
fn an_emissive_texture_half_black_emits_half_the_power_where_it_is_white() {
    let plain = emissive_scene(false).at(0.0);
    let half = emissive_scene(true).at(0.0);
    let (p0, p1) = (plain.emitters.total_power, half.emitters.total_power);
    // Area 4, radiance (1, 0.5, 0.25): pi * 4 * Le; textured: half of it, up to the 32 x 32
    // lattice of each triangle, whose points on the stripes' edge count as white: measured
    // 0.5078.
    let want = Vec3::new(1.0, 0.5, 0.25) * std::f32::consts::PI * 4.0;
    assert!(
        (p0 - want).abs().max_element() < 1e-3 * want.x,
        "{p0} vs {want}"
    );
    let ratio = p1.x / p0.x;
    println!("textured / plain emitter power: {ratio}");
    assert!((ratio - 0.5).abs() < 0.012, "{ratio}");
    // The reference sees the emitter (facing down, at y = 3, rotated by pi about x: its u
    // still runs along x) white on the left, black on the right.
    let tr = Tracer::new(&half);
    let mut r = irad::math::rng(&[3]);
    let up = |x: f32, r: &mut _| {
        irad::reference::radiance(&half, &tr, Vec3::new(x, 1.0, 0.3), Vec3::Y, r)
    };
    let left = up(-0.5, &mut r);
    let right = up(0.5, &mut r);
    println!("left {left}, right {right}");
    assert!((left - Vec3::new(1.0, 0.5, 0.25)).abs().max_element() < 1e-5);
    assert_eq!(right, Vec3::ZERO);
}

/// A cut-out quad at y = 1 above the floor: its left half (u < 0.5) alpha 0, its right half
/// alpha 1; MASK with the default cutoff 0.5.
fn masked_scene() -> Scene {
    let mut g = Gltf::default();
    let floor = g.quad(FLOOR, FLOOR_UV, None, 0);
    let mut up = FLOOR;
    for p in &mut up {
        p[1] = 1.0;
    }
    let leaf = g.quad(up, FLOOR_UV, None, 2);
    let img = g.image(&png(2, 1, &[[255, 255, 255, 0], [255, 255, 255, 255]]));
    let doc = json!({
        "scene": 0, "scenes": [{ "nodes": [0, 1, 2] }],
        "nodes": [{ "mesh": 0 }, { "mesh": 1, "translation": [0.0, 3.0, 0.0], "rotation": [1.0, 0.0, 0.0, 0.0] }, { "mesh": 2 }],
        "meshes": [floor, g.quad(FLOOR, FLOOR_UV, None, 1), leaf],
        "materials": [
            { "pbrMetallicRoughness": { "baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0 } },
            { "emissiveFactor": [1.0, 1.0, 1.0] },
            { "pbrMetallicRoughness": { "baseColorFactor": [0.5, 0.5, 0.5, 1.0], "baseColorTexture": { "index": 0 }, "metallicFactor": 0.0 },
              "alphaMode": "MASK", "doubleSided": true },
        ],
        "textures": [{ "source": 0, "sampler": 0 }],
        "images": [img],
        "samplers": [{ "magFilter": 9728 }],
    });
    load(&g.finish(doc))
}

#[test]
fn alpha_mask_cut_outs_let_rays_and_light_through() {
    let f = masked_scene().at(0.0);
    let tr = Tracer::new(&f);
    // Straight up from the floor: through the cut half to the emitter (y = 3), stopped by
    // the solid half at y = 1.
    let hit = |x: f32| {
        tr.intersect(Vec3::new(x, 0.01, 0.2), Vec3::Y, f32::INFINITY)
            .unwrap()
            .t
    };
    assert!((hit(-0.5) - 2.99).abs() < 1e-3, "{}", hit(-0.5));
    assert!((hit(0.5) - 0.99).abs() < 1e-3, "{}", hit(0.5));
    // Shadow rays too: the floor under the cut half sees the light, under the solid half
    // not.
    let y = Vec3::new(0.0, 3.0, 0.0);
    assert!(!tr.occluded(
        Vec3::new(-0.5, 0.0, 0.2),
        Vec3::Y,
        Vec3::new(-0.5, 3.0, 0.2),
        -Vec3::Y
    ));
    assert!(tr.occluded(
        Vec3::new(0.5, 0.0, 0.2),
        Vec3::Y,
        y + Vec3::X * 0.5,
        -Vec3::Y
    ));
    // No VPL lands on a cut-away point, and some land on the solid half.
    let (mut on_leaf, mut cut) = (0, 0);
    for path in 0..4000 {
        for v in irad::vpl::trace_path(&f, &tr, 7, path) {
            let (tri, p) = (v.tri as usize, v.position);
            if (p.y - 1.0).abs() < 1e-4 {
                on_leaf += 1;
                cut += (p.x < 0.0) as usize;
                assert!(f.tri_material[tri] == 2);
            }
        }
    }
    println!("VPLs on the leaf: {on_leaf}, on its cut half: {cut}");
    assert!(on_leaf > 100);
    assert_eq!(cut, 0);
}

#[test]
fn a_missing_image_is_a_warning_naming_it_and_the_factor_stays() {
    let mut g = Gltf::default();
    let floor = g.quad(FLOOR, FLOOR_UV, None, 0);
    let doc = json!({
        "scene": 0, "scenes": [{ "nodes": [0, 1] }],
        "nodes": [{ "mesh": 0 }, { "mesh": 1, "translation": [0.0, 3.0, 0.0], "rotation": [1.0, 0.0, 0.0, 0.0] }],
        "meshes": [floor, g.quad(FLOOR, FLOOR_UV, None, 1)],
        "materials": [
            { "pbrMetallicRoughness": { "baseColorFactor": [0.3, 0.4, 0.5, 1.0], "baseColorTexture": { "index": 0 }, "metallicFactor": 0.0 } },
            { "emissiveFactor": [1.0, 1.0, 1.0] },
        ],
        "textures": [{ "source": 0 }],
        "images": [{ "uri": "no%20such%20wood.png" }],
    });
    let s = load(&g.finish(doc));
    println!("{:?}", s.warnings);
    assert!(
        s.warnings.iter().any(|w| w.contains("no such wood.png")),
        "{:?}",
        s.warnings
    );
    let f = s.at(0.0);
    let (tri, b1, b2) = at(&f, 0.3, 0.3);
    assert_eq!(f.albedo_at(tri, b1, b2), Vec3::new(0.3, 0.4, 0.5));
}

/// The GPU's direct light and emission on a textured scene against its CPU twin (which reads
/// the textures through `Frame::albedo_at` and `emission_at`): the checker floor lit by the
/// half-black emissive texture, seen from above.
#[test]
fn gpu_textures_agree_with_the_cpu_twin() {
    for backend in common::backends() {
        let (d, e, images) = gpu_against_twin(backend, &checker_lit_by_stripes(), "textures", 1e-6);
        // Measured 1.5e-7 and 1.1e-8 on lavapipe and llvmpipe (float rounding: the GPU
        // samples the same texels by the same rule); reading the factors instead of the
        // textures is off by tens of percent.
        assert!(
            d < 1e-6,
            "{backend:?}: direct light differs from its twin by {d}{images}"
        );
        assert!(
            e < 1e-6,
            "{backend:?}: emission differs from its twin by {e}{images}"
        );
    }
}

/// The checker floor lit by a small emitter with a two-stripe emissive texture, emitting
/// from both sides, seen from above.
fn checker_lit_by_stripes() -> Scene {
    let mut g = Gltf::default();
    let floor = g.quad(FLOOR, FLOOR_UV, None, 0);
    let checker = g.image(&png(2, 2, &CHECKER));
    let stripes = g.image(&png(2, 1, &[[255, 255, 255, 255], [40, 40, 40, 255]]));
    let mut up = FLOOR;
    for p in &mut up {
        p[1] = 0.0;
    }
    let doc = json!({
        "scene": 0, "scenes": [{ "nodes": [0, 1] }],
        "nodes": [{ "mesh": 0 }, { "mesh": 1, "translation": [0.0, 1.5, 0.0], "rotation": [1.0, 0.0, 0.0, 0.0], "scale": [0.3, 1.0, 0.3] }],
        "meshes": [floor, g.quad(up, FLOOR_UV, None, 1)],
        "materials": [
            { "pbrMetallicRoughness": { "baseColorFactor": [0.9, 0.9, 0.9, 1.0], "baseColorTexture": { "index": 0 }, "metallicFactor": 0.0 } },
            { "emissiveFactor": [4.0, 4.0, 4.0], "emissiveTexture": { "index": 1 }, "doubleSided": true },
        ],
        "textures": [{ "source": 0, "sampler": 0 }, { "source": 1, "sampler": 0 }],
        "images": [checker, stripes],
        "samplers": [{ "magFilter": 9728 }],
    });
    let mut scene = load(&g.finish(doc));
    scene
        // Off the symmetric view, so no emitter edge passes exactly through pixel centres
        // (where rasterization and ray casting may break the tie differently).
        .set_camera(
            Vec3::new(0.0137, 3.0, 0.0291),
            Vec3::new(0.0031, 0.0, 0.0017),
            0.9,
        )
        .unwrap();
    scene
}

/// The GPU's direct light and emission against the CPU twin's on `scene` (64 x 64, one sample
/// a pixel): mean |gpu - twin| / twin's mean, for each; where either exceeds `bound`, the
/// images written ([`common::save_images`]), named in a line for the caller's message ("" if
/// none).
fn gpu_against_twin(
    backend: irad::gpu::BackendChoice,
    scene: &Scene,
    name: &str,
    bound: f32,
) -> (f32, f32, String) {
    let (w, h) = (64, 64);
    let mut cfg = crate::common::render_config();
    cfg.sequence.size = irad::config::Size {
        width: w,
        height: h,
    };
    cfg.vpls = 64;
    cfg.quality.light_samples = 16;
    cfg.quality.interleave = 1;
    // Pixel centres, as the twin: no sub-samples and no box-filtered emitter edges.
    cfg.quality.aa = 1;
    cfg.quality.edge_rays = 0;
    cfg.backend = backend;
    let gpu = std::sync::Arc::new(irad::gpu::Gpu::new(backend).unwrap());
    let mut p = irad::frame::Pipeline::new(gpu, scene.clone(), &cfg).unwrap();
    let out = p.render_frame(0, true).unwrap();
    let frame = scene.at(0.0);
    let tracer = Tracer::new(&frame);
    let samples = frame.emitter_samples(cfg.sequence.seed, 16);
    let points = irad::reference::twin::pixel_points(&frame, &tracer, w, h);
    let direct_cpu = irad::reference::twin::direct(&frame, &tracer, &points, w, h, &samples);
    let emission_cpu = irad::reference::twin::emission(&frame, &points, w, h);
    let direct_gpu = out.image.direct.as_ref().unwrap();
    let indirect_gpu = out.image.indirect.as_ref().unwrap();
    let lum = irad::math::luminance;
    let mean = |img: &irad::image::Hdr| {
        img.data.iter().map(|&c| lum(c)).sum::<f32>() / img.data.len() as f32
    };
    let diff = |a: &[Vec3], b: &[Vec3]| {
        a.iter()
            .zip(b)
            .map(|(&x, &y)| lum((x - y).abs()))
            .sum::<f32>()
            / a.len() as f32
    };
    let d = diff(&direct_gpu.data, &direct_cpu.data) / mean(&direct_cpu);
    // The GPU's emission: the frame less its direct and indirect parts.
    let emission_gpu: Vec<Vec3> = out
        .image
        .hdr
        .data
        .iter()
        .zip(&direct_gpu.data)
        .zip(&indirect_gpu.data)
        .map(|((&c, &d), &i)| c - d - i)
        .collect();
    let e = diff(&emission_gpu, &emission_cpu.data) / mean(&emission_cpu).max(1e-12);
    println!("{backend:?}: direct: mean |gpu - twin| / mean = {d:.2e}; emission: {e:.2e}");
    if name == "textures" {
        // The checker's colours reach the image: red- and blue-dominant pixels both.
        let reds = direct_gpu
            .data
            .iter()
            .filter(|c| c.x > 2.0 * c.z && c.x > 0.01)
            .count();
        let blues = direct_gpu
            .data
            .iter()
            .filter(|c| c.z > 2.0 * c.x && c.z > 0.01)
            .count();
        println!("red-dominant {reds}, blue-dominant {blues} pixels");
        assert!(reds > 100 && blues > 100);
    }
    let mut images = String::new();
    if d > bound || e > bound {
        let name = format!("{name}-{backend:?}").to_lowercase();
        let emission_gpu = irad::image::Hdr {
            width: w,
            height: h,
            data: emission_gpu,
        };
        let direct = common::save_images(TEST, &format!("{name}-direct"), direct_gpu, &direct_cpu);
        let emission = common::save_images(
            TEST,
            &format!("{name}-emission"),
            &emission_gpu,
            &emission_cpu,
        );
        images = format!("; direct {direct}; emission {emission}");
    }
    (d, e, images)
}

/// Alpha MASK on the GPU: the G-buffer sees the floor through the leaf's cut half, and the
/// shadow maps let light through it, as the CPU twin's rays do.
#[test]
fn gpu_alpha_mask_cut_outs_agree_with_the_cpu_twin() {
    let mut scene = masked_scene();
    scene
        .set_camera(
            Vec3::new(0.0137, 2.5, 0.0291),
            Vec3::new(0.0031, 0.0, 0.0017),
            1.0,
        )
        .unwrap();
    for backend in common::backends() {
        let (d, _, images) = gpu_against_twin(backend, &scene, "alpha-mask", 1.5e-3);
        // Measured 9.7e-4 on both (shadow-map texels at the edge of the leaf's shadow);
        // without the cut-outs on the GPU the camera sees the leaf where the twin sees the
        // floor through it, and the floor under the hole is in shadow: 0.61.
        assert!(
            d < 1.5e-3,
            "{backend:?}: direct light differs from its twin by {d}{images}"
        );
    }
}

#[test]
fn texcoords_read_into_the_frame_follow_mirrored_winding() {
    // A mirroring node (negative scale) swaps two corners of each triangle: the UVs must
    // follow, so the same surface point reads the same texel either way.
    let s = checker_scene(json!({ "magFilter": 9728 }), None, [1.0, 1.0, 1.0, 1.0]);
    let f = s.at(0.0);
    let (tri, b1, b2) = at(&f, -0.5, 0.5);
    let a = f.albedo_at(tri, b1, b2);
    let mut m = s.clone();
    m.nodes[0].local = irad::scene::Local::Trs {
        translation: Vec3::ZERO,
        rotation: glam::Quat::IDENTITY,
        scale: Vec3::new(1.0, 1.0, -1.0),
    };
    let fm = m.at(0.0);
    // Mirrored in z: the point (x, z) of the mirrored floor is the original's (x, -z).
    let (tri, b1, b2) = at(&fm, -0.5, -0.5);
    let b = fm.albedo_at(tri, b1, b2);
    assert_eq!(a, b);
    let _ = Vec2::ZERO;
}

/// The whole GPU frame against the reference path tracer on a textured room: a checker floor
/// (REPEAT, the UVs scaled by 2 so it tiles), a back wall with vertex colours, lit by the
/// two-stripe emissive texture from both sides. Indirect light reflects off textured
/// surfaces both ways: VPLs carry the texel's albedo, the gather applies the receiver's.
#[test]
fn gpu_agrees_with_the_reference_on_a_textured_room() {
    let backend = common::backend();
    let mut g = Gltf::default();
    let floor = g.quad(FLOOR, FLOOR_UV, None, 0);
    let wall = g.quad(
        [[-1., 0., -1.], [1., 0., -1.], [1., 2., -1.], [-1., 2., -1.]],
        FLOOR_UV,
        Some([
            [255, 60, 60, 255],
            [60, 255, 60, 255],
            [60, 60, 255, 255],
            [255, 255, 255, 255],
        ]),
        2,
    );
    // A white ceiling facing down and a checkered left wall facing +x close the room on
    // three more sides, so light bounces.
    let ceiling = g.quad(
        [[-1., 2., -1.], [1., 2., -1.], [1., 2., 1.], [-1., 2., 1.]],
        FLOOR_UV,
        None,
        2,
    );
    let left = g.quad(
        [[-1., 0., -1.], [-1., 2., -1.], [-1., 2., 1.], [-1., 0., 1.]],
        FLOOR_UV,
        None,
        0,
    );
    let checker = g.image(&png(2, 2, &CHECKER));
    let stripes = g.image(&png(2, 1, &[[255, 255, 255, 255], [40, 40, 40, 255]]));
    let doc = json!({
        "scene": 0, "scenes": [{ "nodes": [0, 1, 2, 3, 4] }],
        "nodes": [{ "mesh": 0 }, { "mesh": 1, "translation": [0.0, 1.2, 0.0], "rotation": [1.0, 0.0, 0.0, 0.0], "scale": [0.3, 1.0, 0.3] }, { "mesh": 2 }, { "mesh": 3 }, { "mesh": 4 }],
        "meshes": [floor, g.quad(FLOOR, FLOOR_UV, None, 1), wall, ceiling, left],
        "materials": [
            { "pbrMetallicRoughness": { "baseColorFactor": [0.9, 0.9, 0.9, 1.0], "metallicFactor": 0.0,
              "baseColorTexture": { "index": 0, "extensions": { "KHR_texture_transform": { "scale": [2.0, 2.0] } } } } },
            { "emissiveFactor": [4.0, 4.0, 4.0], "emissiveTexture": { "index": 1 }, "doubleSided": true,
              "pbrMetallicRoughness": { "baseColorFactor": [0.0, 0.0, 0.0, 1.0] } },
            { "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0 } },
        ],
        "textures": [{ "source": 0, "sampler": 0 }, { "source": 1, "sampler": 1 }],
        "images": [checker, stripes],
        "samplers": [{ "magFilter": 9728 }, { "magFilter": 9728 }],
        "extensionsUsed": ["KHR_texture_transform"],
    });
    let mut scene = load(&g.finish(doc));
    scene
        .set_camera(Vec3::new(0.3, 1.6, 2.4), Vec3::new(0.0, 0.4, -0.4), 0.9)
        .unwrap();
    let (w, h) = (64, 64);
    let mut cfg = crate::common::render_config();
    cfg.sequence.size = irad::config::Size {
        width: w,
        height: h,
    };
    cfg.vpls = 1024;
    // Enough emitter samples that where they fall on the two-stripe emitter hardly matters
    // (with the default 32 the frame came out +2.2%, with 256 -0.02%).
    cfg.quality.light_samples = 256;
    cfg.backend = backend;
    let gpu = std::sync::Arc::new(irad::gpu::Gpu::new(backend).unwrap());
    let mut p = irad::frame::Pipeline::new(gpu, scene.clone(), &cfg).unwrap();
    let out = p.render_frame(0, true).unwrap();
    let frame = scene.at(0.0);
    let tracer = Tracer::new(&frame);
    let reference = irad::reference::render(
        &frame,
        &tracer,
        &irad::reference::ReferenceSettings {
            width: w,
            height: h,
            spp: 1024,
            seed: 3,
            ..Default::default()
        },
        &|| {},
    );
    let e = irad::metrics::frame_error(&out.image.hdr, &reference).unwrap();
    let ind = out.image.indirect.as_ref().unwrap();
    let lum = irad::math::luminance;
    let share = ind.data.iter().map(|&c| lum(c)).sum::<f32>()
        / out.image.hdr.data.iter().map(|&c| lum(c)).sum::<f32>();
    println!(
        "gpu vs reference: relMSE {:.5}, relative bias {:+.5}; indirect {:.3} of the frame",
        e.rel_mse, e.rel_bias, share
    );
    // Measured on lavapipe: relMSE 0.00140, relative bias +0.0052 (20% of the frame is
    // indirect light), with the 2x2 interleave `resolve::interleave_for` gives this 64x64 frame
    // (0.00109 and +0.0043 with the 4x4 one before). With the lamp's back face winning the
    // depth test over its emitting twin on a quarter of two pixels, -0.013; with the light's
    // edges from the 2x2 sub-samples instead of box-filtered, relMSE 0.00211.
    let (rel_mse_bound, bias_bound) = (0.0032, 0.0065);
    let mut images = String::new();
    if e.rel_mse > rel_mse_bound || e.rel_bias.abs() > bias_bound {
        images = format!(
            " ({})",
            common::save_images(TEST, "textured-room", &out.image.hdr, &reference)
        );
    }
    assert!(share > 0.1, "the room has indirect light to test: {share}");
    assert!(e.rel_mse <= rel_mse_bound, "relMSE {}{images}", e.rel_mse);
    assert!(
        e.rel_bias.abs() <= bias_bound,
        "relative bias {}{images}",
        e.rel_bias
    );
}

/// An image with neither a uri nor a bufferView (the gltf crate's `Image::source` panics on
/// it, as fuzzed files found) is a warning naming it; an embedded image without a mimeType
/// decodes by its content.
#[test]
fn images_without_a_source_or_a_mime_type_do_not_panic() {
    let mut g = Gltf::default();
    let floor = g.quad(FLOOR, FLOOR_UV, None, 0);
    let mut img = g.image(&png(2, 2, &CHECKER));
    img.as_object_mut().unwrap().remove("mimeType");
    let doc = json!({
        "scene": 0, "scenes": [{ "nodes": [0, 1] }],
        "nodes": [{ "mesh": 0 }, { "mesh": 1, "translation": [0.0, 3.0, 0.0], "rotation": [1.0, 0.0, 0.0, 0.0] }],
        "meshes": [floor, g.quad(FLOOR, FLOOR_UV, None, 1)],
        "materials": [
            { "pbrMetallicRoughness": { "baseColorFactor": [1.0, 1.0, 1.0, 1.0], "baseColorTexture": { "index": 0 }, "metallicFactor": 0.0 } },
            { "emissiveFactor": [1.0, 1.0, 1.0], "emissiveTexture": { "index": 1 } },
        ],
        "textures": [{ "source": 0, "sampler": 0 }, { "source": 1 }],
        "images": [img, { "name": "ghost" }],
        "samplers": [{ "magFilter": 9728 }],
    });
    let s = load(&g.finish(doc));
    println!("{:?}", s.warnings);
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("'ghost'") && w.contains("neither a uri nor a bufferView")),
        "{:?}",
        s.warnings
    );
    let f = s.at(0.0);
    let (tri, b1, b2) = at(&f, -0.5, -0.5);
    assert!((f.albedo_at(tri, b1, b2).x - lin(200)).abs() < 1e-6);
    // The emitter falls back to its factor.
    assert!((f.emitters.total_power.x - 4.0 * std::f32::consts::PI).abs() < 1e-4);
}

/// An emitter with an alpha MASK emits nothing where it is cut away: its power counts only
/// the solid half, and its emitter samples carry light only there.
#[test]
fn a_cut_out_emitter_emits_only_where_it_is_solid() {
    let mut g = Gltf::default();
    let floor = g.quad(FLOOR, FLOOR_UV, None, 0);
    let img = g.image(&png(2, 1, &[[255, 255, 255, 0], [255, 255, 255, 255]]));
    let doc = json!({
        "scene": 0, "scenes": [{ "nodes": [0, 1] }],
        "nodes": [{ "mesh": 0 }, { "mesh": 1, "translation": [0.0, 3.0, 0.0], "rotation": [1.0, 0.0, 0.0, 0.0] }],
        "meshes": [floor, g.quad(FLOOR, FLOOR_UV, None, 1)],
        "materials": [
            { "pbrMetallicRoughness": { "baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0 } },
            { "emissiveFactor": [1.0, 1.0, 1.0], "alphaMode": "MASK",
              "pbrMetallicRoughness": { "baseColorFactor": [0.0, 0.0, 0.0, 1.0], "baseColorTexture": { "index": 0 } } },
        ],
        "textures": [{ "source": 0, "sampler": 0 }],
        "images": [img],
        "samplers": [{ "magFilter": 9728 }],
    });
    let f = load(&g.finish(doc)).at(0.0);
    // Area 4, radiance 1: pi * 4 whole, half of it solid (up to the 32 x 32 lattice, as for
    // the half-black emissive texture).
    let ratio = f.emitters.total_power.x / (4.0 * std::f32::consts::PI);
    println!("cut-out emitter power / whole: {ratio}");
    assert!((ratio - 0.5).abs() < 0.012, "{ratio}");
    // Emitter samples on the cut half (x < 0) carry nothing, on the solid half light.
    let samples = f.emitter_samples(5, 64);
    let (cut, solid): (Vec<&irad::scene::EmitterSample>, Vec<_>) =
        samples.iter().partition(|s| s.position.x < 0.0);
    assert!(cut.iter().all(|s| s.radiance == Vec3::ZERO));
    assert!(solid.iter().all(|s| s.radiance.x > 0.0));
    assert!(!cut.is_empty() && !solid.is_empty());
}
