//! Issue 11 item 6: the GPU agrees with the reference on geometry as Blender exports it. The
//! test writes a Cornell box whose walls are thin boxes (2 cm), whose light is a closed
//! emissive cube 1 cm under the ceiling, whose white is glTF's default albedo 1, with a box in
//! the middle, and holds `irad render` to `irad reference`.
//!
//! What went wrong there: 41% of the light leaves the cube's top face into the 1 cm gap, where
//! paths bounce between two white surfaces (about a hundred times before they get out), so
//! most VPLs sit in the gap. Their ISM tiles held the room behind the cube's top: the point
//! set is spread by area, so a surface 1 cm away gets a few points over most of the tile, and
//! the floor's points land between them; those VPLs lit the room as if nothing were in the
//! way (2.9x too bright, relMSE 2.96 in this test before). Now each VPL also splats the first
//! surfaces it sees along a grid of rays, each covering its cell of the tile
//! (`gpu::ism::near_points`), and paths are no longer cut at 16 bounces, which had lost the
//! light that leaves the gap late (0.58 of the reference with the ISM fixed).
//!
//! Issue 23 item 1 sweeps the gap (1 cm to touching, double- and single-sided): light paths
//! no longer live inside closed meshes (the lamp's back-emitting twins shone into it, and an
//! offset through a gap thinner than itself put paths inside the ceiling), nor start there
//! (the twins are left out of the emitters a frame draws from), and a vertex in a
//! crevice keeps its VPL by a coin on how much of its lobe gets out (`vpl::crevice`); see
//! docs/math.md, "Light that cannot get out".

use crate::common;
use base64::Engine;
use irad::gpu::Compensate;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// One embedded buffer; meshes are boxes.
#[derive(Default)]
struct Doc {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
}

impl Doc {
    fn accessor(&mut self, bytes: &[u8], count: usize, ty: &str, component: u32) -> usize {
        let (b, v, a) = (&mut self.bin, &mut self.views, &mut self.accessors);
        crate::common::gltf::accessor(b, v, a, (bytes, count, ty, component))
    }

    /// An axis-aligned box from `lo` to `hi`, faces outward, as Blender writes a cube.
    fn cuboid(&mut self, name: &str, lo: [f32; 3], hi: [f32; 3], material: usize) {
        let ([x0, y0, z0], [x1, y1, z1]) = (lo, hi);
        let faces = [
            [[x1, y0, z0], [x1, y1, z0], [x1, y1, z1], [x1, y0, z1]],
            [[x0, y0, z0], [x0, y0, z1], [x0, y1, z1], [x0, y1, z0]],
            [[x0, y1, z0], [x0, y1, z1], [x1, y1, z1], [x1, y1, z0]],
            [[x0, y0, z0], [x1, y0, z0], [x1, y0, z1], [x0, y0, z1]],
            [[x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]],
            [[x0, y0, z0], [x0, y1, z0], [x1, y1, z0], [x1, y0, z0]],
        ];
        let p: Vec<f32> = faces.iter().flatten().flatten().copied().collect();
        let i: Vec<u32> = (0..6u32)
            .flat_map(|f| [0, 1, 2, 0, 2, 3].map(|k| 4 * f + k))
            .collect();
        let pa = self.accessor(bytemuck::cast_slice(&p), 24, "VEC3", 5126);
        self.accessors[pa]["min"] = json!(lo);
        self.accessors[pa]["max"] = json!(hi);
        let ia = self.accessor(bytemuck::cast_slice(&i), 36, "SCALAR", 5125);
        self.meshes.push(json!({ "name": name, "primitives": [
            { "attributes": { "POSITION": pa }, "indices": ia, "material": material }] }));
        self.nodes
            .push(json!({ "name": name, "mesh": self.meshes.len() - 1 }));
    }
}

/// The Blender-like Cornell box: room [-1,1]^3 open at +z, walls 2 cm thick, the light a
/// 50 x 5 x 40 cm cube 1 cm under the ceiling (emission strength 10), a 60 x 80 x 60 cm box.
fn blender_cornell() -> Value {
    cornell_with_gap(0.01, true)
}

/// [`blender_cornell`] with the light's top `gap` under the ceiling's underside (0: touching)
/// and every material double- or single-sided.
fn cornell_with_gap(gap: f32, double_sided: bool) -> Value {
    let t = 0.02;
    let mut d = Doc::default();
    let (white, red, green, light) = (0, 1, 2, 3);
    d.cuboid(
        "floor",
        [-1. - t, -1. - t, -1. - t],
        [1. + t, -1., 1.],
        white,
    );
    d.cuboid(
        "ceiling",
        [-1. - t, 1., -1. - t],
        [1. + t, 1. + t, 1.],
        white,
    );
    d.cuboid("back", [-1. - t, -1., -1. - t], [1. + t, 1., -1.], white);
    d.cuboid("left", [-1. - t, -1., -1.], [-1., 1., 1.], red);
    d.cuboid("right", [1., -1., -1.], [1. + t, 1., 1.], green);
    d.cuboid(
        "light",
        [-0.25, 0.94 - gap, -0.2],
        [0.25, 1. - gap, 0.2],
        light,
    );
    d.cuboid("box", [-0.3, -1., -0.3], [0.3, -0.2, 0.3], white);
    let mut nodes = d.nodes.clone();
    let sides = |m: Value| {
        let mut m = m;
        m["doubleSided"] = json!(double_sided);
        m
    };
    nodes.push(json!({ "name": "camera", "camera": 0, "translation": [0.0, 0.0, 3.9] }));
    json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{ "nodes": (0..nodes.len()).collect::<Vec<_>>() }],
        "nodes": nodes,
        "meshes": d.meshes,
        "materials": [
            // Blender's white: no baseColorFactor, so glTF's default albedo 1.
            sides(json!({ "name": "white", "pbrMetallicRoughness": { "metallicFactor": 0.0 } })),
            sides(json!({ "name": "red", "pbrMetallicRoughness": { "baseColorFactor": [0.57, 0.043, 0.044, 1.0], "metallicFactor": 0.0 } })),
            sides(json!({ "name": "green", "pbrMetallicRoughness": { "baseColorFactor": [0.105, 0.378, 0.076, 1.0], "metallicFactor": 0.0 } })),
            sides(json!({ "name": "light", "pbrMetallicRoughness": { "metallicFactor": 0.0 }, "emissiveFactor": [1.0, 1.0, 1.0],
              "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 10.0 } } })),
        ],
        "cameras": [{ "type": "perspective", "perspective": { "yfov": 39.3f32.to_radians(), "znear": 0.1 } }],
        "accessors": d.accessors,
        "bufferViews": d.views,
        "buffers": [{
            "byteLength": d.bin.len(),
            "uri": format!("data:application/octet-stream;base64,{}",
                base64::engine::general_purpose::STANDARD.encode(&d.bin)),
        }],
    })
}

fn irad(args: &[&str]) {
    let o = common::irad(args);
    assert!(
        o.status.success(),
        "irad {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&o.stderr)
    );
}

fn tmp(name: &str) -> PathBuf {
    let d = common::fresh_dir(&format!("gap-{name}"));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn read(dir: &Path) -> irad::image::Hdr {
    irad::image::Hdr::read(&dir.join("frame_0000.exr")).unwrap()
}

#[test]
fn gpu_matches_the_reference_on_a_blender_style_cornell_box() {
    let dir = tmp("scene");
    let scene = dir.join("blender-cornell.gltf");
    std::fs::write(&scene, serde_json::to_vec(&blender_cornell()).unwrap()).unwrap();
    let s = scene.to_str().unwrap();
    let (gpu, reference) = (dir.join("gpu"), dir.join("reference"));
    let size = "48x48";
    irad(&[
        "reference",
        s,
        "--size",
        size,
        "--spp",
        "1024",
        "--out",
        reference.to_str().unwrap(),
    ]);
    irad(&[
        "render",
        s,
        "--size",
        size,
        "--frames",
        "0",
        "--vpls",
        "1024",
        // The sampler the tolerances below were measured with (one seed: across seeds 1-3
        // uniform's bias runs -0.016 to -0.116, mh's -0.037 to -0.057).
        "--sampler",
        "uniform",
        "--out",
        gpu.to_str().unwrap(),
    ]);
    let (g, r) = (read(&gpu), read(&reference));
    let e = irad::metrics::frame_error(&g, &r).unwrap();
    println!(
        "GPU against the reference: mean {:+.4} ({:+.2}%), relMSE {:.4}",
        e.bias,
        100.0 * e.rel_bias,
        e.rel_mse
    );
    // Before: +28% mean and relMSE 2.96 (64x64, 256 VPLs); the image away from the light
    // 2.2-3.5x the reference's. At 386cd23: -3.4%, relMSE 0.59 (light paths inside the
    // closed lamp leaking through the ISMs, by chance near the mean for seed 1: +115% to
    // +6368% over seeds 1-3 at 32x32). Without compensation -15.5% and relMSE 0.220 (the
    // VPLs' mean is below the reference's at a 1 cm gap: see the sweep below and docs/math.md,
    // "Light that cannot get out"). With `--compensate auto` tracing 64 paths a pixel: +4.2%
    // and relMSE 0.228 when written; +16.4% and 0.199 at stop 48 (its judge is the default
    // reference, whose roulette leaves part of the gap's light out); +13.4% and 0.211 with the
    // compensation walking the gap. At this gap single seeds run -10% to +17% (the sweep
    // below), so the bound on the mean stays at 20%.
    let mut images = String::new();
    if e.rel_bias.abs() >= 0.20 || e.rel_mse >= 0.30 {
        images = format!(
            " ({})",
            common::save_images("thin_gap", "blender-cornell", &g, &r)
        );
    }
    assert!(e.rel_bias.abs() < 0.20, "mean {:+.3}{images}", e.rel_bias);
    assert!(e.rel_mse < 0.30, "relMSE {}{images}", e.rel_mse);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The gaps of the sweep (metres; the room is 2 m wide): 1 cm, 1 mm, 0.1 mm, 0.01 mm, touching.
const GAPS: [f32; 5] = [0.01, 0.001, 1e-4, 1e-5, 0.0];

use irad::reference::RR_CAP_DEPTH;

/// The judge of a row, by gap: the bounce from which its roulette is capped, its samples a
/// pixel (`spp` from 1 mm down) and the seeds whose mean it is. Every cap has the same expected
/// image, but not the same image in thousands of samples: out of a 1 cm gap 97% of the light
/// leaves within 256 bounces (median 35, `benches/gap_escape.py`), so capped from 256 it
/// arrives at weight 1 and the reference converges (two 8192-spp images differ by relMSE
/// 0.136; capped from 3 by 0.89, that light arriving on a few paths weighted thousands-fold,
/// and most images darker than their expected value). At 65536 samples a pixel (about 35 s a
/// side here) it is within relMSE 0.008-0.010 of the mean of 16 such references of 8192, where
/// a 1024-sample judge would differ from the GPU's frames by its own noise (about 1).
///
/// Out of a 1 mm gap 21% of the light leaves within 256 bounces, 42% within 1024 and 98.5%
/// within 16384. Capped from 256 the reference shows part of it (four of 8192 spp, the judge
/// before, have a mean 38% under the true image's), and a camera path that finds the gap and
/// stays is a firefly. Capped from 65536 it shows nearly all of it, but pixel by pixel it is
/// far too noisy to judge by (two of 8192 spp differ by relMSE 10): the judge is the mean of
/// 16 (seeds 1-16, 4 s each here), whose image mean is within 1.7% of the true one and whose
/// 4 x 4 blocks within relMSE about 0.023, and the 1 mm rows are compared on those blocks
/// ([`blocks`]; docs/math.md, "Out of a 1 mm gap"). From 0.1 mm down no path gets in (a gap
/// thinner than 1e-4 of the scene, 0.2 mm here, ends the paths that enter it:
/// `Tracer::seals`), so they keep the default (docs/math.md, "What the reference can show of a
/// gap", "Gaps thinner than the scene resolves").
fn judge(gap: f32, spp: u32) -> (u32, u32, u64) {
    if gap >= 0.01 {
        (256, spp.max(65536), 1)
    } else if gap >= 0.001 {
        (1 << 16, spp.max(8192), 16)
    } else {
        (RR_CAP_DEPTH, spp, 1)
    }
}

/// The judge of the sweep's row (`gap`, double-sided) at `size`^2, from `spp` samples a pixel
/// ([`judge`]), made once for the tests that share it.
fn judge_frame(
    scene: &irad::scene::Scene,
    (gap, double): (f32, bool),
    size: u32,
    spp: u32,
) -> irad::image::Hdr {
    type Judges = std::collections::HashMap<(u32, bool, u32, u32), irad::image::Hdr>;
    static JUDGES: std::sync::Mutex<Option<Judges>> = std::sync::Mutex::new(None);
    let (cap, spp, seeds) = judge(gap, spp);
    let mut judges = JUDGES.lock().unwrap();
    let judges = judges.get_or_insert_with(Default::default);
    judges
        .entry((gap.to_bits(), double, size, spp))
        .or_insert_with(|| {
            let refs: Vec<_> = (1..=seeds)
                .map(|s| common::reference_capped_from(scene, size, spp, s, cap))
                .collect();
            mean_of(&refs)
        })
        .clone()
}

/// The per-pixel mean of `images` (all of one size; at least one).
fn mean_of(images: &[irad::image::Hdr]) -> irad::image::Hdr {
    let mut mean = images[0].clone();
    for (px, i) in mean.data.iter_mut().enumerate() {
        *i = images.iter().map(|r| r.data[px]).sum::<glam::Vec3>() / images.len() as f32;
    }
    mean
}

/// The 4 x 4 blocks' means of `img` (its sides multiples of 4): how the 1 mm rows are compared
/// with their judge, whose pixels are too noisy ([`judge`]).
fn blocks(img: &irad::image::Hdr) -> irad::image::Hdr {
    let (w, h) = (img.width / 4, img.height / 4);
    let mut out = irad::image::Hdr::new(w, h);
    for (i, b) in out.data.iter_mut().enumerate() {
        let (bx, by) = (i as u32 % w, i as u32 / w);
        *b = (0..16)
            .map(|k| img.data[((4 * by + k / 4) * img.width + 4 * bx + k % 4) as usize])
            .sum::<glam::Vec3>()
            / 16.0;
    }
    out
}

/// The error of a frame of the sweep against its row's judge: pixel by pixel, but on 4 x 4
/// blocks at 1 mm ([`judge`]).
fn row_error(gap: f32, g: &irad::image::Hdr, r: &irad::image::Hdr) -> irad::metrics::FrameError {
    // The rows whose judge is the mean of 16 deep references (1 mm) are compared on blocks.
    if judge(gap, 0).2 > 4 {
        irad::metrics::frame_error(&blocks(g), &blocks(r)).unwrap()
    } else {
        irad::metrics::frame_error(g, r).unwrap()
    }
}

/// Frame 0 of `scene` at `size`^2 with 1024 VPLs of `sampler` (default settings otherwise, as
/// `irad render` makes it, but for `compensate`), seed `seed`.
fn gpu_frame(
    scene: &irad::scene::Scene,
    size: u32,
    sampler: irad::vpl::sampler::SamplerKind,
    seed: u64,
    compensate: Compensate,
) -> irad::image::Hdr {
    let mut cfg = common::render_config();
    cfg.sequence.size = irad::config::Size {
        width: size,
        height: size,
    };
    cfg.vpls = 1024;
    cfg.sampler.kind = sampler;
    cfg.sequence.seed = seed;
    cfg.quality.compensate = compensate;
    cfg.backend = common::backend();
    let gpu = std::sync::Arc::new(irad::gpu::Gpu::new(cfg.backend).unwrap());
    let mut p = irad::frame::Pipeline::new(gpu, scene.clone(), &cfg).unwrap();
    p.render_frame(0, true).unwrap().image.hdr
}

/// One row of the sweep: the gap, whether double-sided, and the GPU frame's error against
/// the reference for each seed.
type Row = (f32, bool, Vec<irad::metrics::FrameError>);

/// The sweep: every gap, double- and single-sided, the GPU frame (`compensate` paths a pixel)
/// of each seed against the reference (32 x 32, 1024 samples a pixel); prints the table.
fn sweep(
    sampler: irad::vpl::sampler::SamplerKind,
    seeds: &[u64],
    compensate: Compensate,
) -> Vec<Row> {
    sweep_against(sampler, seeds, compensate, 1024)
}

/// [`sweep`] against a reference of `spp` samples a pixel.
fn sweep_against(
    sampler: irad::vpl::sampler::SamplerKind,
    seeds: &[u64],
    compensate: Compensate,
    spp: u32,
) -> Vec<Row> {
    let size = 32;
    println!(
        "gap sweep, {sampler:?} seeds {seeds:?}, --compensate {compensate}, 1024 VPLs, \
         {size}x{size}, reference {spp} spp (1 cm and 1 mm: `judge`; 1 mm on 4 x 4 blocks)"
    );
    println!("| gap | sides | relMSE (largest) | bias: mean (each seed) |");
    let mut rows = Vec::new();
    for double in [true, false] {
        for gap in GAPS {
            let scene = common::quads::load(&cornell_with_gap(gap, double));
            let r = judge_frame(&scene, (gap, double), size, spp);
            let sides = if double { "double" } else { "single" };
            let errors: Vec<_> = seeds
                .iter()
                .map(|&seed| {
                    let g = gpu_frame(&scene, size, sampler, seed, compensate);
                    let e = row_error(gap, &g, &r);
                    if e.rel_mse > 0.2 || common::show_images() {
                        let name = format!("{}mm-{sides}-c{compensate}-s{seed}", gap * 1e3);
                        common::save_images(TEST, &name, &g, &r);
                    }
                    e
                })
                .collect();
            let biases: Vec<String> = errors
                .iter()
                .map(|e| format!("{:+.1}%", 100.0 * e.rel_bias))
                .collect();
            println!(
                "| {:>5.2} mm | {sides} | {:.4} | {:+.1}% ({}) | {sampler:?}",
                gap * 1e3,
                largest_mse(&errors),
                100.0 * mean_bias(&errors),
                biases.join(", ")
            );
            rows.push((gap, double, errors));
        }
    }
    rows
}

fn largest_mse(errors: &[irad::metrics::FrameError]) -> f64 {
    errors.iter().map(|e| e.rel_mse).fold(0.0, f64::max)
}

fn mean_bias(errors: &[irad::metrics::FrameError]) -> f64 {
    errors.iter().map(|e| e.rel_bias).sum::<f64>() / errors.len() as f64
}

const TEST: &str = "thin_gap";

/// Issue 23 item 1 at the defaults: whatever the gap between a closed emissive slab and an
/// albedo-1 ceiling, its VPLs light only what they see, and what the distance clamp cannot
/// give (the camera's view into the gap's mouth, the ceiling beside the lamp, lit by emitter
/// points closer than the clamp) is path-traced: every lamp of the sweep sends 43-46% of its
/// light within the clamp, so `--compensate auto` traces 64 paths a pixel
/// (`resolve::compensate`). Over seeds 1-4 the mean bias is within 5% at every gap, double- and
/// single-sided. Before (at 386cd23, 3 seeds): double-sided +80% to +18822% (light paths
/// inside the closed lamp and, through offsets, inside the ceiling); single-sided 1 mm relMSE
/// 3.46. Without compensation (the test below) the rows are -0.1% to -4.4%, and -25% at 1 cm.
#[test]
fn the_gap_sweep_against_the_reference() {
    let rows = sweep(
        irad::vpl::sampler::SamplerKind::Uniform,
        &[1, 2, 3, 4],
        Compensate::Auto,
    );
    // Measured (docs/math.md, "ISMs by a surface"): the largest relMSE 0.043 and 0.044 at
    // 1 cm (+1.1%, +1.3%), 0.030 at 0.1 mm and less, the mean bias +2.5% to +2.7%; at 1 mm, on
    // 4 x 4 blocks against the true image, 0.031 and 0.030, the mean -2.0% and -2.8% (seeds
    // -9.3% to +5.3%). Stop 53, before the ISMs' near-field planes: 0.042 and 0.043 at 1 cm,
    // +2.1% to +2.3% below 1 mm, -2.6% and -3.4% at 1 mm. Stop 52, before the sliver's
    // rounds: -5.5% and -4.9% (seeds -10.7% to -0.9%; over 16 seeds -2.2% +- 1.2% and -2.2% +-
    // 1.6%).
    // At the old ray offset, against its judge (stop 51), -0.5% and -2.3%, and over 16 seeds
    // -4.4% and -3.3%; with the walkers' rounds each a hypercube of its own (stop 50), -6.4%
    // and -5.2%; with cosine lobes on the way out, and none from the vertices deep in the gap
    // whose coin was skipped (stop 49), -8.1% and -6.5%; before the compensation walked the gap
    // (stop 48), 0.052 and 0.050 at 1 mm, 27-29% under; before light paths followed the gap's
    // light out (1024 bounces), 0.060-0.076 on blocks.
    assert_rows(&rows, [0.05, 0.04, 0.035]);
}

/// The sweep with the default sampler, `mh` (seeds 1-4). Measured (docs/math.md, "ISMs by a
/// surface"): the largest relMSE 0.045 and 0.035 at 1 cm, 0.022 and less below 1 mm, the mean
/// bias -0.6% to +1.4%; at 1 mm, on blocks against the true image, 0.023 and 0.025, the mean
/// -0.3% and -1.8% (seeds -6.3% to +2.0%; over 16 seeds -1.3% and -1.9%,
/// [`the_default_samplers_one_mm_rows_over_16_seeds`]). Stop 53: -0.9% and -2.4%; stop 52:
/// -2.8% and -3.7%;
/// stop 51, at the old ray offset against its judge: -0.5% and -1.6%; stop 50: -6.5% and
/// -4.6%; stop 49: -8.7% and -7.0%; before the compensation walked the gap, 0.049 and 0.050,
/// 27-29% under.
#[test]
fn the_gap_sweep_with_the_default_sampler() {
    let rows = sweep(
        irad::vpl::sampler::SamplerKind::Mh,
        &[1, 2, 3, 4],
        Compensate::Auto,
    );
    assert_rows(&rows, [0.05, 0.04, 0.03]);
}

/// The 1 mm rows' mean bias over seeds 1-4: within 5% of the true image, as issue 23 asks of
/// every row. At 1 mm a frame's mean swings from seed to seed by about 3% (the camera's view
/// into the gap's mouth, and the light paths out of it), so four seeds' mean has a standard
/// error of about 1.6%, and the judge's own is 1.1% (docs/math.md, "The mouth's sliver, and
/// the judge's own noise"); [`the_default_samplers_one_mm_rows_over_16_seeds`] holds `mh`'s
/// bias to 5% over 16 seeds too. Measured at stop 54: seeds 1-4 -2.8% to -0.3% (stop 53:
/// -3.4% to -0.9%). At stop 52,
/// before a pixel that sees the gap through a sliver took rounds for its points in it, the
/// rows' frames swung by about 5%: -5.5% to -2.8%, and this bound was 8%; at stop 51, at the
/// old offset of 1e-4 (a fifth of the gap), whose judge carried 8% too much of the gap's light,
/// 5%; stop 50 8%; stop 49: seeds 1-4 6.5-8.7% under; stop 48: 27-29%.
const ONE_MM: f64 = 0.05;

/// Every row's largest relMSE within its bound (`[1 cm, 1 mm, the gaps below]`) and its mean
/// bias within 5% ([`ONE_MM`] at 1 mm).
fn assert_rows(rows: &[Row], bounds: [f64; 3]) {
    for (gap, double, e) in rows {
        let (mse, bias) = (largest_mse(e), mean_bias(e));
        let (mse_bound, under) = match *gap {
            g if g >= 0.01 => (bounds[0], 0.05),
            g if g >= 0.001 => (bounds[1], ONE_MM),
            _ => (bounds[2], 0.05),
        };
        assert!(
            mse <= mse_bound && (-under..=0.05).contains(&bias),
            "gap {gap} m, double-sided {double}: relMSE {mse:.4} (bound {mse_bound}), mean bias {bias:+.3}"
        );
    }
}

/// The same sweep with `--compensate off`: the VPLs alone. No light leaks through the gap,
/// but the clamp darkens the gap's mouth and the ceiling beside the lamp (docs/math.md,
/// "Light that cannot get out").
#[test]
fn the_gap_sweep_without_compensation() {
    let rows = sweep(
        irad::vpl::sampler::SamplerKind::Uniform,
        &[1],
        Compensate::Paths(0),
    );
    for (gap, double, e) in rows {
        let e = &e[0];
        // Measured with seed 1 (docs/math.md): both sides alike now that the double-sided
        // lamp's inside starts no light path. At 1 cm the VPLs' mean is far below the judge
        // (-24.2% both sides, relMSE 0.051: the camera sees into the gap's mouth, whose inside
        // the clamped gather cannot light, and what a crevice's VPLs light nearby is the
        // compensation's). At 1 cm now 0.047, -23.9%. At 1 mm, on blocks against the true image,
        // 0.051, -22.7% (the mouth darker still than with the compensation; stop 51, against the
        // judge at the old ray offset, 8% brighter: 0.055, -33.2%); below, at most 0.028 and
        // +0.2%. Each at most about 10% over.
        let (mse, under) = match gap {
            g if g >= 0.01 => (0.06, 0.27),
            g if g >= 0.001 => (0.056, 0.25),
            _ => (0.035, 0.05),
        };
        assert!(
            e.rel_mse <= mse && (-under..=0.05).contains(&e.rel_bias),
            "gap {gap} m, double-sided {double}: relMSE {:.4} (bound {mse}), bias {:+.3} (at most {under} under)",
            e.rel_mse,
            e.rel_bias
        );
    }
}

/// The sweep at the defaults against 8192-spp references (a measurement: `--ignored`): how
/// much of the largest relMSEs of [`the_gap_sweep_against_the_reference`] is the 1024-spp
/// reference's own noise.
#[test]
#[ignore]
fn the_gap_sweep_against_8192_spp() {
    sweep_against(
        irad::vpl::sampler::SamplerKind::Uniform,
        &[1, 2, 3, 4],
        Compensate::Auto,
        8192,
    );
}

/// Light paths end inside a closed mesh only when the camera is outside it: a room modelled
/// as a closed box with its faces out (Blender's cube, scaled) and seen from inside keeps its
/// light; seen from outside, no VPL is inside it. And no VPL of the sweep's double-sided lamp
/// lies inside the lamp (its back-emitting twins shine into it).
#[test]
fn light_paths_live_in_a_closed_box_only_when_the_camera_is_inside() {
    use irad::vpl::trace_paths;
    let room = |camera_z: f32| {
        let mut q = common::quads::Quads::default();
        let grey = q.material(0.5, 0.0, true);
        let light = q.material(0.0, 10.0, true);
        q.cube([-1.0; 3], [1.0; 3], grey);
        q.quad(
            [0.0, 0.9, 0.0],
            [0.2, 0.0, 0.0],
            [0.0, 0.0, 0.2],
            light,
            json!({}),
        );
        q.camera([0.0, 0.0, camera_z], 1.0);
        common::quads::load(&q.finish())
    };
    let inside_vpls = |scene: &irad::scene::Scene| {
        let f = scene.at(0.0);
        let t = irad::trace::Tracer::new(&f);
        let v = trace_paths(&f, &t, 1, 0, 2000);
        let inside = v
            .iter()
            .filter(|v| v.position.abs().max_element() <= 1.0 + 1e-4)
            .count();
        (v.len(), inside)
    };
    let (all, inside) = inside_vpls(&room(0.5));
    assert!(
        inside > 2000 && inside == all,
        "camera inside: {inside} of {all} VPLs inside"
    );
    let (all, inside) = inside_vpls(&room(3.0));
    assert_eq!((all, inside), (0, 0), "camera outside: VPLs inside the box");
    let lamp = common::quads::load(&cornell_with_gap(0.01, true));
    let f = lamp.at(0.0);
    let t = irad::trace::Tracer::new(&f);
    let v = trace_paths(&f, &t, 1, 0, 4000);
    let in_lamp = v
        .iter()
        .filter(|v| {
            let p = v.position;
            p.x.abs() < 0.25 - 1e-4
                && p.z.abs() < 0.2 - 1e-4
                && p.y > 0.93 + 1e-4
                && p.y < 0.99 - 1e-4
        })
        .count();
    assert_eq!(in_lamp, 0, "{in_lamp} of {} VPLs inside the lamp", v.len());
}

/// A frame's light paths start only where a closed lamp's light gets out: the sweep's
/// double-sided lamp (a closed slab, `doubleSided: true`) has a back-emitting twin under each
/// face that shines into it (`trace::solids`). Drawn in proportion to power with the rest,
/// the twins took half of the paths, which ended at once, and half of the direct light's
/// samples (`Frame::keep_emitters` now leaves them out). Of the paths the uniform sampler
/// draws for 1024 VPLs, 0.885-0.942 leave a VPL (seeds 1-4; the rest leave the box through
/// its open front or end on a crevice's coin); before, 0.425-0.490.
#[test]
fn a_closed_lamps_light_paths_start_outside_it() {
    let scene = common::quads::load(&cornell_with_gap(0.01, true));
    for seed in 1..=4 {
        let mut cfg = common::render_config();
        cfg.sequence.size = irad::config::Size {
            width: 32,
            height: 32,
        };
        cfg.vpls = 1024;
        cfg.sampler.kind = irad::vpl::sampler::SamplerKind::Uniform;
        cfg.sequence.seed = seed;
        cfg.quality.compensate = Compensate::Paths(0);
        cfg.backend = common::backend();
        let gpu = std::sync::Arc::new(irad::gpu::Gpu::new(cfg.backend).unwrap());
        let mut p = irad::frame::Pipeline::new(gpu, scene.clone(), &cfg).unwrap();
        let sel = p.render_frame(0, false).unwrap().selection;
        let lit: std::collections::BTreeSet<u64> = sel.vpls.iter().map(|v| v.path).collect();
        let share = lit.len() as f64 / sel.paths as f64;
        assert!(
            share >= 0.8,
            "seed {seed}: {} of {} paths left a VPL ({share:.3})",
            lit.len(),
            sel.paths
        );
    }
}

/// The 1 mm gap's light gets out on the light paths, and leaves VPLs on its way out
/// (`vpl::paths::DEEP`, `vpl::paths::EXIT`; docs/math.md, "Out of a 1 mm gap"). Of the lamp's
/// light, its top's share (0.2 m^2 of its 0.508) goes into the gap, and nearly all of it leaves
/// within the 16384 bounces a path may now take (98.5% in the model of `benches/gap_escape.py`;
/// 42% within the 1024 before). A path that leaves from a vertex sealed in the gap, or from one
/// deep in it whose coin was skipped, leaves a VPL on its way out: beyond the lamp's top,
/// leaving out across its edge with the power the path carries, its light in a fan about the
/// plates' plane (`vpl::fan_lobe`). Over 4000 paths (seed 1) those VPLs carry 0.407
/// (double-sided) and 0.411 of the lamp top's light, the rest leaving from vertices at the
/// mouth with a way out, whose own VPLs carry it; from sealed vertices alone (stop 49), 0.267
/// and 0.271; with paths of 1024 bounces, 0.081 and 0.082.
#[test]
fn a_one_mm_gaps_light_gets_out_on_the_light_paths() {
    use irad::vpl::paths::EXIT;
    for double in [true, false] {
        let scene = common::quads::load(&cornell_with_gap(0.001, double));
        let mut f = scene.at(0.0);
        let t = irad::trace::Tracer::new(&f);
        t.keep_lit_emitters(&mut f);
        let lamp = irad::math::luminance(f.emitters.total_power);
        let paths = 4000u64;
        let (mut exits, mut power) = (0usize, 0.0f64);
        for path in 0..paths {
            for v in irad::vpl::trace_path(&f, &t, 1, path) {
                if v.depth < EXIT {
                    continue;
                }
                exits += 1;
                power += irad::math::luminance(v.power) as f64;
                let p = v.position;
                let inside = p.y > 0.999 - 1e-4 && p.x.abs() < 0.25 && p.z.abs() < 0.2;
                assert!(!inside, "an exit VPL in the gap at {p}");
                // Beyond the lamp's top, facing out across the edges it is beyond.
                let beyond = |c: f32, e: f32| (c.abs() > e) as i32 as f32 * c.signum();
                let out = glam::Vec3::new(beyond(p.x, 0.25), 0.0, beyond(p.z, 0.2));
                assert!(
                    out != glam::Vec3::ZERO && v.normal.dot(out) > 0.0,
                    "exit VPL at {p} facing {}",
                    v.normal
                );
                // Its fan about the plates' plane, on the side the path left to.
                let fan = v.fan.expect("an exit VPL without its fan");
                assert!(
                    fan.y.abs() > 0.999 && v.normal.dot(fan) > 0.0,
                    "exit VPL at {p} leaving along {} with its fan about {fan}",
                    v.normal
                );
            }
        }
        let top = 0.2 / 0.508;
        let share = power / paths as f64 / (lamp as f64 * top);
        println!(
            "double-sided {double}: {exits} VPLs on the way out of {paths} paths, their power \
             over the lamp top's {share:.3}"
        );
        assert!((0.35..=0.46).contains(&share), "{share}");
    }
}

/// Light that leaves a crevice carries the power it went in with: between the albedo-1 lamp
/// top and ceiling a light path goes on without Russian roulette (`vpl::crevice`), so the
/// first VPL out of the gap weighs what the path weighed when it entered. Each light path of
/// the sweep's lamps starts with the same power (the lamp's, its emission uniform), so over
/// the paths whose VPL of one bounce lies in the gap and whose VPL of the next lies out of it
/// (kept whole: `near` none), that VPL's power over the lamp's is 1 but for the few bounces at
/// the gap's mouth that see out and keep the roulette's 1/0.99, and for a coin there. Before,
/// the median was 1/0.99 for every bounce in the gap (at 1 cm a path leaves after 35 of them).
/// Gaps 1 cm and 1 mm, double- and single-sided (below, no path gets in).
#[test]
fn light_leaves_a_crevice_with_the_power_it_entered_with() {
    for gap in [0.01f32, 0.001] {
        for double in [true, false] {
            let scene = common::quads::load(&cornell_with_gap(gap, double));
            let mut f = scene.at(0.0);
            let t = irad::trace::Tracer::new(&f);
            t.keep_lit_emitters(&mut f);
            let lamp = irad::math::luminance(f.emitters.total_power);
            let in_gap = |p: glam::Vec3| {
                p.y >= 1.0 - gap - 1e-4
                    && p.y <= 1.0 + 1e-4
                    && p.x.abs() <= 0.25
                    && p.z.abs() <= 0.2
            };
            let mut ratios: Vec<f32> = (0..4000u64)
                .flat_map(|path| {
                    let v = irad::vpl::trace_path(&f, &t, 1, path);
                    let out: Vec<f32> = v
                        .windows(2)
                        .filter(|w| {
                            w[1].depth == w[0].depth + 1
                                && in_gap(w[0].position)
                                && !in_gap(w[1].position)
                                && w[1].near.is_none()
                        })
                        .map(|w| irad::math::luminance(w[1].power) / lamp)
                        .collect();
                    out
                })
                .collect();
            ratios.sort_by(f32::total_cmp);
            let q = |x: f64| ratios[((ratios.len() - 1) as f64 * x) as usize];
            println!(
                "gap {gap} m, double-sided {double}: {} paths out of the gap, power out / in: median {:.4}, 90th percentile {:.4}, largest {:.4}",
                ratios.len(),
                q(0.5),
                q(0.9),
                q(1.0)
            );
            assert!(ratios.len() >= 20, "{} paths out", ratios.len());
            assert!(
                (q(0.5) - 1.0).abs() <= 0.03 && q(0.9) <= 1.25,
                "gap {gap}, double-sided {double}: median {}, 90th percentile {}",
                q(0.5),
                q(0.9)
            );
        }
    }
}

/// Every lamp of the sweep sends more than `resolve::NEAR_FIELD_SHARE` of its light into the
/// ceiling within the clamp, so `--compensate auto` compensates it (and a render with
/// `--compensate off` says what that leaves out: tests/cli/near_field.rs); the Cornell box's
/// lamp sends none, and gets no compensation.
#[test]
fn every_lamp_of_the_sweep_is_compensated() {
    let share = |scene: &irad::scene::Scene| {
        let f = scene.at(0.0);
        let t = irad::trace::Tracer::new(&f);
        let cfg = common::render_config();
        let clamp = irad::resolve::sampler_params(&cfg, &f, &t).clamp;
        (irad::compensation::near_field_share(&f, &t, clamp), clamp)
    };
    let auto = |s: f32| irad::resolve::compensate(Compensate::Auto, Some(s));
    for double in [true, false] {
        for gap in GAPS {
            let (s, clamp) = share(&common::quads::load(&cornell_with_gap(gap, double)));
            println!("gap {gap} m, double-sided {double}: clamp {clamp:.4}, near field {s:.3}");
            assert!(
                s >= irad::resolve::NEAR_FIELD_SHARE,
                "gap {gap}, {double}: {s}"
            );
            assert_eq!(auto(s), irad::resolve::AUTO_COMPENSATE);
        }
    }
    let cornell = irad::scene::builtin::load("cornell").unwrap().unwrap();
    let (s, _) = share(&cornell);
    assert_eq!((s, auto(s)), (0.0, 0));
}

/// The 1 mm rows of `samplers` over 16 seeds against their judge, the true image ([`judge`], on
/// blocks), printed as a table: (double-sided, sampler, mean bias, its standard error, relMSE
/// median and largest) for each.
fn one_mm_rows_over_16_seeds(
    samplers: &[irad::vpl::sampler::SamplerKind],
) -> Vec<(bool, irad::vpl::sampler::SamplerKind, f64, f64, f64, f64)> {
    let seeds: Vec<u64> = (1..=16).collect();
    println!(
        "| sides | sampler | mean bias | standard error | relMSE (median, largest) | each seed |"
    );
    println!("| --- | --- | --- | --- | --- | --- |");
    let mut rows = Vec::new();
    for double in [true, false] {
        let scene = common::quads::load(&cornell_with_gap(0.001, double));
        let r = judge_frame(&scene, (0.001, double), 32, 1024);
        for &sampler in samplers {
            let errors: Vec<_> = seeds
                .iter()
                .map(|&seed| {
                    let g = gpu_frame(&scene, 32, sampler, seed, Compensate::Auto);
                    row_error(0.001, &g, &r)
                })
                .collect();
            let n = errors.len() as f64;
            let mean = mean_bias(&errors);
            let var = errors
                .iter()
                .map(|e| (e.rel_bias - mean).powi(2))
                .sum::<f64>()
                / (n - 1.0);
            let mut mse: Vec<f64> = errors.iter().map(|e| e.rel_mse).collect();
            let each: Vec<String> = errors
                .iter()
                .map(|e| format!("{:+.0} ({:.3})", 100.0 * e.rel_bias, e.rel_mse))
                .collect();
            mse.sort_by(f64::total_cmp);
            let row = (
                double,
                sampler,
                mean,
                (var / n).sqrt(),
                mse[mse.len() / 2],
                mse[mse.len() - 1],
            );
            println!(
                "| {} | {sampler:?} | {:+.1}% | {:.1}% | {:.4}, {:.4} | {} |",
                if double { "double" } else { "single" },
                100.0 * row.2,
                100.0 * row.3,
                row.4,
                row.5,
                each.join(" ")
            );
            rows.push(row);
        }
    }
    rows
}

/// Issue 23 item 1 at 1 mm, where a frame's mean swings from seed to seed by about 3% (the
/// camera's view into the gap's mouth, a hundredth of a pixel high, carries a quarter of the
/// image): the default sampler's rows, both sides, over 16 seeds against the true image,
/// their mean bias within 5%, the median relMSE within 0.025 and every seed's within 0.05
/// (measured at stop 54: -1.3% +- 0.8% and -1.9% +- 0.8%, medians 0.017 and 0.015, the
/// largest 0.023 and 0.025; stop 53: -1.8% and -2.5%, the largest 0.023 and 0.024; at stop 52, before a pixel that sees the gap through a sliver
/// took rounds for its points in it, -1.8% +- 0.9% and -2.2% +- 1.3%, and the largest 0.023
/// and 0.058, seed 15 single-sided, one pixel of the mouth at three times its mean). About 3
/// minutes here.
#[test]
fn the_default_samplers_one_mm_rows_over_16_seeds() {
    for (double, _, mean, se, median, largest) in
        one_mm_rows_over_16_seeds(&[irad::vpl::sampler::SamplerKind::Mh])
    {
        assert!(
            mean.abs() <= 0.05 && median <= 0.025 && largest <= 0.05,
            "double-sided {double}: mean bias {:+.1}% +- {:.1}%, relMSE median {median:.4}, \
             largest {largest:.4}",
            100.0 * mean,
            100.0 * se
        );
    }
}

/// Both samplers' 1 mm rows over 16 seeds ([`one_mm_rows_over_16_seeds`]; a measurement:
/// `--ignored`, about 7 minutes): docs/math.md, "The mouth's sliver, and the judge's own noise"
/// (stop 53: -1.8% to -2.5%, standard errors 0.8-1.2%, relMSE medians 0.015-0.018, every seed
/// within 0.029; stop 52: -1.8% to -2.2%, standard errors 0.9-1.6%, the largest 0.058; stop
/// 51, at the old ray offset and against its judge: -4.5% to -3.3%).
#[test]
#[ignore]
fn the_one_mm_rows_over_16_seeds() {
    use irad::vpl::sampler::SamplerKind;
    one_mm_rows_over_16_seeds(&[SamplerKind::Uniform, SamplerKind::Mh]);
}

/// The 1 cm and 1 mm rows against references that carry the gap's light (a measurement:
/// `--ignored`; docs/math.md, "Light that cannot get out"). With roulette capped at 0.95 from
/// bounce 3 (the default, as Mitsuba 3), the light that leaves a 1 cm gap after its median 35
/// bounces arrives on a few paths weighted up to thousands-fold; capped from bounce 256 it
/// arrives at weight 1 (97% of it leaves within 256 bounces, `benches/gap_escape.py`). Prints
/// each reference's own noise (relMSE between two seeds, 8192 spp each, both caps), and the
/// GPU frames of seeds 1-4 (`uniform`, as the sweep, and `mh`, the default) against the mean
/// of four references capped from 256 (32768 spp).
#[test]
#[ignore]
fn the_wide_gaps_against_references_that_carry_the_gaps_light() {
    println!("| gap | sides | reference noise, cap from 3 | from 256 | mean: from 3, from 256 | sampler | GPU vs 4 x 8192 spp from 256: relMSE | bias |");
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    for gap in [0.01, 0.001] {
        for double in [true, false] {
            let scene = common::quads::load(&cornell_with_gap(gap, double));
            let early: Vec<_> = (1..=2)
                .map(|s| common::reference_capped_from(&scene, 32, 8192, s, 3))
                .collect();
            let late: Vec<_> = (1..=4)
                .map(|s| common::reference_capped_from(&scene, 32, 8192, s, 256))
                .collect();
            let noise = |r: &[irad::image::Hdr]| irad::metrics::frame_error(&r[0], &r[1]).unwrap();
            let judge = mean_of(&late);
            for sampler in [
                irad::vpl::sampler::SamplerKind::Uniform,
                irad::vpl::sampler::SamplerKind::Mh,
            ] {
                let errors: Vec<_> = (1..=4)
                    .map(|seed| {
                        let g = gpu_frame(&scene, 32, sampler, seed, Compensate::Auto);
                        irad::metrics::frame_error(&g, &judge).unwrap()
                    })
                    .collect();
                let each = |f: &dyn Fn(&irad::metrics::FrameError) -> String| {
                    errors.iter().map(f).collect::<Vec<_>>().join(", ")
                };
                println!(
                    "| {} mm | {} | {:.3} | {:.3} | {:.3}, {:.3} | {sampler:?} | {} | {} |",
                    gap * 1e3,
                    if double { "double" } else { "single" },
                    noise(&early).rel_mse,
                    noise(&late).rel_mse,
                    (early[0].mean() + early[1].mean()).element_sum() / 6.0,
                    judge.mean().element_sum() / 3.0,
                    each(&|e| format!("{:.3}", e.rel_mse)),
                    each(&|e| format!("{:+.1}%", 100.0 * e.rel_bias)),
                );
            }
        }
    }
}

/// The 1 mm rows against references that carry nearly all of the gap's light (a
/// measurement: `--ignored`, about 3 minutes; docs/math.md, "The 1 mm gap's true image"): the
/// mean of 16 references of 8192 spp capped from bounce 65536 (98.5% of the light caught in a
/// 1 mm gap leaves within 16384 bounces, `benches/gap_escape.py`), whose image means give the
/// true image's mean within their standard error, against the row's judge ([`judge`], capped
/// from 256) and the GPU's frames (`mh`, seeds 1-4): mean and bias over the whole image, over
/// the room below the lamp (rows 7 on) and over the rows that see the gap's mouth (3-5).
/// Pixel by pixel these references are far too noisy to judge a frame by (two of them differ
/// by relMSE 10, a pixel of the mouth reaching 30-60).
#[test]
#[ignore]
fn the_one_mm_rows_against_references_capped_from_65536() {
    let region = |img: &irad::image::Hdr, rows: std::ops::Range<usize>| {
        let px = &img.data[rows.start * 32..rows.end * 32];
        px.iter().map(|&c| irad::math::luminance(c)).sum::<f32>() / px.len() as f32
    };
    let regions =
        |img: &irad::image::Hdr| [region(img, 0..32), region(img, 7..32), region(img, 3..6)];
    println!("| sides | image | whole: mean (standard error) | room | mouth |");
    println!("| --- | --- | --- | --- | --- |");
    for double in [true, false] {
        let scene = common::quads::load(&cornell_with_gap(0.001, double));
        let sides = if double { "double" } else { "single" };
        let deep: Vec<_> = (1..=16)
            .map(|s| common::reference_capped_from(&scene, 32, 8192, s, 1 << 16))
            .collect();
        let truth = regions(&mean_of(&deep));
        let early: Vec<_> = (1..=4)
            .map(|s| common::reference_capped_from(&scene, 32, 8192, s, 256))
            .collect();
        let each: Vec<[f32; 3]> = deep.iter().map(regions).collect();
        let se = |k: usize| {
            let m = truth[k];
            let var = each.iter().map(|r| (r[k] - m).powi(2)).sum::<f32>() / 15.0;
            (var / 16.0).sqrt()
        };
        println!(
            "| {sides} | 16 x 8192 spp from 65536 | {:.4} ({:.4}) | {:.4} ({:.4}) | {:.3} ({:.3}) |",
            truth[0], se(0), truth[1], se(1), truth[2], se(2)
        );
        let row = |name: String, img: &irad::image::Hdr| {
            let r = regions(img);
            let b = |k: usize| 100.0 * (r[k] / truth[k] - 1.0);
            println!(
                "| {sides} | {name} | {:.4} {:+.1}% | {:.4} {:+.1}% | {:.3} {:+.1}% |",
                r[0],
                b(0),
                r[1],
                b(1),
                r[2],
                b(2)
            );
        };
        row(
            "4 x 8192 spp from 256 (the judge before)".into(),
            &mean_of(&early),
        );
        for seed in 1..=4 {
            let g = gpu_frame(
                &scene,
                32,
                irad::vpl::sampler::SamplerKind::Mh,
                seed,
                Compensate::Auto,
            );
            row(format!("GPU, mh, seed {seed}"), &g);
        }
    }
}

/// The light inside the 1 cm gap, term by term (a measurement: `--ignored`, about 2 minutes;
/// docs/math.md, "Light that cannot get out"). At points of the ceiling's underside and the
/// lamp's top, 2 mm to 20 cm in from the lamp's front edge, what the renderer's estimate is
/// made of, each term with exact visibility and averaged over the VPLs of seeds 1-256 (1024,
/// `uniform`, drawn as a frame draws them): the direct light clamped as with the compensation
/// on, the VPLs' gather clamped, and the compensation's mean over 250 paths a seed; against
/// the reference's radiance there (100000 paths capped from bounce 4096). Each with its
/// standard error.
#[test]
#[ignore]
fn the_light_inside_a_one_cm_gap_term_by_term() {
    use irad::math::luminance;
    use rand::Rng;
    let scene = common::quads::load(&cornell_with_gap(0.01, true));
    let frame = scene.at(0.0);
    let tracer = irad::trace::Tracer::new(&frame);
    // (depth in from the front edge, ray to the point from inside the gap): the lamp's top
    // at y = 0.99, the ceiling's underside at y = 1, the front edge at z = 0.2.
    let depths = [0.002f32, 0.01, 0.03, 0.1, 0.2];
    let probes: Vec<(f32, glam::Vec3, glam::Vec3)> = depths
        .iter()
        .flat_map(|&dz| {
            [
                (dz, glam::Vec3::new(0.013, 0.991, 0.2 - dz), glam::Vec3::Y),
                (
                    dz,
                    glam::Vec3::new(0.013, 0.999, 0.2 - dz),
                    glam::Vec3::NEG_Y,
                ),
            ]
        })
        .collect();
    let points: Vec<_> = probes
        .iter()
        .map(|&(_, o, d)| {
            let h = tracer.intersect(o, d, 1.0).unwrap();
            irad::reference::twin::SurfacePoint::seen(&frame, &h, d)
        })
        .collect();
    // Many VPL sets, few compensation paths each: the VPLs' placement, not the paths, is what
    // moves the terms inside the gap (16 sets left them uncertain by 15-20%).
    let seeds = 256u64;
    let mut cfg = common::render_config();
    cfg.vpls = 1024;
    cfg.sampler.kind = irad::vpl::sampler::SamplerKind::Uniform;
    let params = irad::resolve::sampler_params(&cfg, &frame, &tracer);
    let clamp = params.clamp;
    // The frame the pipeline draws from (Frame::keep_emitters).
    let mut lit = frame.clone();
    tracer.keep_lit_emitters(&mut lit);
    // Per point and term: the sum over seeds and the sum of squares.
    let mut terms = vec![[(0.0f64, 0.0f64); 3]; probes.len()];
    for seed in 1..=seeds {
        let mut sampler = irad::vpl::sampler::Sampler::new(irad::vpl::sampler::SamplerParams {
            seed,
            ..params.clone()
        });
        let vpls = sampler.select(&lit, &tracer, 0).shaded;
        let samples = lit.emitter_samples(seed, 4096);
        let light = irad::compensation::Light {
            samples: &samples,
            vpls: &vpls,
            clamp,
        };
        let nearby = irad::compensation::Nearby::new(&vpls, &tracer);
        for (k, s) in points.iter().enumerate() {
            let rho = frame.albedo_at(s.tri as usize, s.b.x, s.b.y);
            let direct: glam::Vec3 = samples
                .iter()
                .filter_map(|l| {
                    let (e, q, nq) = l.irradiance_at(s.x, s.n)?;
                    let near = ((s.x - q).length_squared() / (clamp * clamp)).min(1.0);
                    (!tracer.occluded(s.x, s.n, q, nq)).then_some(e * near)
                })
                .sum::<glam::Vec3>()
                * rho
                / std::f32::consts::PI;
            // As the frame has it: the GPU's VPLs, and a crevice's VPLs within their reach (the
            // compensation adds those at the point a pixel sees).
            let gather: glam::Vec3 = vpls
                .iter()
                .filter(|v| v.near.is_none_or(|r| (v.position - s.x).length() <= r))
                .filter(|v| !tracer.occluded(s.x, s.n, v.position, v.normal))
                .map(|v| v.radiance_at(s.x, s.n, rho, clamp))
                .sum();
            let mut r = irad::math::rng(&[seed, k as u64, 0x9a9]);
            let n = 250;
            let comp: glam::Vec3 = (0..n)
                .map(|_| {
                    let u = glam::Vec2::new(r.random(), r.random());
                    let bounces = irad::compensation::MAX_BOUNCES;
                    irad::compensation::path(
                        &lit,
                        &tracer,
                        s,
                        (&light, &nearby),
                        (u, bounces),
                        &mut r,
                    )
                })
                .sum::<glam::Vec3>()
                / n as f32;
            for (t, c) in terms[k].iter_mut().zip([direct, gather, comp]) {
                let c = luminance(c) as f64;
                *t = (t.0 + c, t.1 + c * c);
            }
        }
    }
    // The mean over seeds and its standard error.
    let stat = |(sum, sq): (f64, f64)| {
        let n = seeds as f64;
        let mean = sum / n;
        (mean, ((sq / n - mean * mean).max(0.0) / (n - 1.0)).sqrt())
    };
    println!("| depth | surface | emission | direct (clamped) | VPLs (clamped) | compensation | sum | reference | sum / reference | reference's clamped share | its compensated share |");
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for (k, &(dz, o, d)) in probes.iter().enumerate() {
        let s = &points[k];
        let le = luminance(frame.emission_at(s.tri as usize, s.b.x, s.b.y)) as f64;
        let mut r = irad::math::rng(&[9, k as u64]);
        let n = 100000;
        let (reference, reference_se) = {
            let (mut sum, mut sq) = (0.0f64, 0.0f64);
            for _ in 0..n {
                let l = irad::reference::radiance_capped_from(&frame, &tracer, o, d, 4096, &mut r);
                let l = luminance(l) as f64;
                (sum, sq) = (sum + l, sq + l * l);
            }
            let mean = sum / n as f64;
            (
                mean,
                ((sq / n as f64 - mean * mean).max(0.0) / (n - 1) as f64).sqrt(),
            )
        };
        let [(direct, _), (gather, gather_se), (comp, comp_se)] = terms[k].map(stat);
        // The reference's radiance split as the renderer splits it: over the first hit's
        // distance d, the share min(1, d^2 / clamp^2) (the direct light and the VPLs') and the
        // rest (the compensation's).
        let (mut clamped, mut compensated) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let u = glam::Vec2::new(r.random(), r.random());
            let w = irad::math::cosine_hemisphere(s.n, u);
            let o = tracer.offset(s.x, s.n, w);
            let Some(h) = tracer.intersect(o, w, f32::INFINITY) else {
                continue;
            };
            let l = irad::reference::radiance_capped_from(&frame, &tracer, o, w, 4096, &mut r);
            let q = ((h.t / clamp) as f64).powi(2).min(1.0);
            let rho = frame.albedo_at(s.tri as usize, s.b.x, s.b.y).x as f64;
            clamped += rho * q * luminance(l) as f64 / n as f64;
            compensated += rho * (1.0 - q) * luminance(l) as f64 / n as f64;
        }
        let sum = le + direct + gather + comp;
        let ratio = sum / reference;
        let ratio_se = (gather_se.powi(2) + comp_se.powi(2) + (ratio * reference_se).powi(2))
            .sqrt()
            / reference;
        println!(
            "| {:.0} mm | {} | {le:.1} | {direct:.2} | {gather:.1} ± {gather_se:.1} | {comp:.1} ± {comp_se:.1} | {sum:.1} | {reference:.1} ± {reference_se:.1} | {ratio:.2} ± {ratio_se:.2} | {clamped:.1} | {compensated:.1} |",
            dz * 1e3,
            if d.y > 0.0 { "ceiling" } else { "lamp top" },
        );
    }
}

/// A frame's light of the sweep's scene at `gap` as the compensation reads it: the frame its
/// light paths start from, its tracer, and the light (`uniform`, 1024 VPLs, seed `seed`, the
/// default clamp).
fn frame_light(
    gap: f32,
    double: bool,
    seed: u64,
) -> (
    irad::scene::Frame,
    irad::trace::Tracer,
    Vec<irad::vpl::ShadedVpl>,
    Vec<irad::scene::EmitterSample>,
    f32,
) {
    let scene = common::quads::load(&cornell_with_gap(gap, double));
    let frame = scene.at(0.0);
    let tracer = irad::trace::Tracer::new(&frame);
    let mut cfg = common::render_config();
    cfg.vpls = 1024;
    cfg.sampler.kind = irad::vpl::sampler::SamplerKind::Uniform;
    let params = irad::resolve::sampler_params(&cfg, &frame, &tracer);
    let mut lit = frame.clone();
    tracer.keep_lit_emitters(&mut lit);
    let mut sampler = irad::vpl::sampler::Sampler::new(irad::vpl::sampler::SamplerParams {
        seed,
        ..params.clone()
    });
    let vpls = sampler.select(&lit, &tracer, 0).shaded;
    let samples = lit.emitter_samples(seed, 1024);
    (lit, tracer, vpls, samples, params.clamp)
}

/// The compensation's paths carry the light inside a 1 mm gap's mouth (docs/math.md, "Into a
/// 1 mm gap"): at the points of the ceiling's underside that the camera sees 0.5 to 3 mm in from
/// the lamp's front edge, their mean over 8000 paths a point (seed 1's VPLs) is the reference's
/// radiance there (8000 paths capped from bounce 65536), within 10% pooled over the points,
/// double- and single-sided (measured 0.973 and 1.028; their standard errors about 3% each).
/// The light there comes from hundreds of bounces between the lamp's top and the ceiling;
/// before, the compensation's paths split each bounce's light between the clamped VPLs (a
/// sixteenth of the deep ones) and 256 bounces of their own, and carried 7-16% of it; walking
/// the gap but cut at 16384 bounces, 0.92-0.96.
#[test]
fn the_compensation_carries_the_light_inside_a_one_mm_gap() {
    use irad::compensation::{path, Light, Nearby, MAX_BOUNCES};
    use irad::math::luminance;
    use rand::Rng;
    use rayon::prelude::*;
    for double in [true, false] {
        let (frame, tracer, vpls, samples, clamp) = frame_light(0.001, double, 1);
        let light = Light {
            samples: &samples,
            vpls: &vpls,
            clamp,
        };
        let nearby = Nearby::new(&vpls, &tracer);
        let cam = frame.camera.position;
        let n = 8000u64;
        let (mut comp, mut reference) = (0.0f64, 0.0f64);
        for (k, dz) in [0.0005f32, 0.001, 0.002, 0.003].into_iter().enumerate() {
            let d = (glam::Vec3::new(0.013, 1.0, 0.2 - dz) - cam).normalize();
            let h = tracer.intersect(cam, d, f32::INFINITY).unwrap();
            let s = irad::reference::twin::SurfacePoint::seen(&frame, &h, d);
            assert!((s.x.y - 1.0).abs() < 1e-4 && s.x.z < 0.2, "{}", s.x);
            let sums: (f64, f64) = (0..n)
                .into_par_iter()
                .map(|i| {
                    let mut r = irad::math::rng(&[k as u64, i, double as u64]);
                    let u = glam::Vec2::new(r.random(), r.random());
                    let c = path(
                        &frame,
                        &tracer,
                        &s,
                        (&light, &nearby),
                        (u, MAX_BOUNCES),
                        &mut r,
                    );
                    let l = irad::reference::radiance_capped_from(
                        &frame,
                        &tracer,
                        cam,
                        d,
                        1 << 16,
                        &mut r,
                    );
                    (luminance(c) as f64, luminance(l) as f64)
                })
                .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
            println!(
                "double-sided {double}, {:.1} mm in: compensation {:.0}, reference {:.0}",
                dz * 1e3,
                sums.0 / n as f64,
                sums.1 / n as f64
            );
            comp += sums.0;
            reference += sums.1;
        }
        let ratio = comp / reference;
        println!("double-sided {double}: compensation / reference {ratio:.3}");
        assert!(
            (ratio - 1.0).abs() < 0.1,
            "double-sided {double}: {ratio:.3}"
        );
    }
}

/// A pixel that sees into a 1 mm gap through a sliver thinner than its paths' strata takes
/// rounds of compensation paths until about [`irad::compensation::SLIVER_POINTS`] of its
/// camera points lie in the gap (docs/math.md, "Into a 1 mm gap"): at 32 x 32 the camera sees
/// into the gap over about a hundredth of a pixel's height, which a round of 64 paths can miss,
/// and a round that finds no light there asks for few more. The pixels of the lamp's front
/// edge (row 3, columns 13-18, seeds 1-8, both sides) each take more than twice
/// [`irad::compensation::MAX_ROUNDS`] (measured: 48-64). Without the finer camera rays
/// that look for the gap in a pixel across an edge, seed 4's first pixel took 5; without the
/// walkers' floor (stop 52), seed 3's fourth, a walker whose first round's variance asked for
/// 6; before the sliver's rounds (stop 53) they took 8-16.
///
/// And with them the light of that row's compensation varies less from seed to seed: its
/// standard deviation over the 8 seeds, relative to its mean, under 0.2 (measured 0.132
/// double-sided, 0.094 single-sided; with `SLIVER_POINTS` 64, 0.098 and 0.148; with at most 16
/// rounds, `SLIVER_POINTS` 0, 0.219 and 0.270: a walk's light is heavy-tailed, and with the 10
/// or so points in the gap of 16 rounds one seed's row came out at 1.4 and 1.6 times the mean).
#[test]
fn pixels_that_see_into_a_one_mm_gap_take_every_round() {
    use irad::compensation::{compensate_in_rounds, Light, MAX_ROUNDS};
    for double in [true, false] {
        let mut row = Vec::new();
        for seed in 1..=8u64 {
            let (frame, tracer, vpls, samples, clamp) = frame_light(0.001, double, seed);
            let light = Light {
                samples: &samples,
                vpls: &vpls,
                clamp,
            };
            let seen = vec![glam::Vec3::ZERO; 32 * 32];
            let out = compensate_in_rounds(
                &frame,
                &tracer,
                (32, 32),
                &light,
                (64, &seen, MAX_ROUNDS),
                seed,
            );
            let rounds: Vec<u32> = (13..=18)
                .map(|x| out.iter().find(|o| o.0 == 3 * 32 + x).map_or(0, |o| o.2))
                .collect();
            let light: f64 = out
                .iter()
                .filter(|o| o.0 / 32 == 3)
                .map(|o| irad::math::luminance(o.1) as f64)
                .sum();
            println!("double-sided {double}, seed {seed}: rounds {rounds:?}, row 3 {light:.1}");
            assert!(
                rounds.iter().all(|&k| k > 2 * MAX_ROUNDS),
                "double-sided {double}, seed {seed}: {rounds:?}"
            );
            row.push(light);
        }
        let n = row.len() as f64;
        let mean = row.iter().sum::<f64>() / n;
        let sd = (row.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        println!(
            "double-sided {double}: row 3's compensation {mean:.1}, spread {:.3}",
            sd / mean
        );
        assert!(sd < 0.2 * mean, "double-sided {double}: {row:?}");
    }
}
