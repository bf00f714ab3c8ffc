//! A deterministic mutation fuzzer over the glTF loader (issue 11 item 5): built-in scenes,
//! as .gltf and as .glb, mutated in their JSON values and in their bytes. Every case must
//! load or be refused within a time bound, without a panic, and a scene that loads must
//! evaluate to finite triangles, a usable camera and finite emitted power.
//!
//! Case kinds 4 and 5 are the hostile ones of issue 24: huge node translations and vertices,
//! buffer and image URIs naming special files (`/dev/zero`) or leading out of the folder, and
//! emissive textures black almost everywhere (then a loaded scene is also path-traced at 4 x 4,
//! which once panicked); kind 5 loads with `allow_outside_paths`.
//!
//! The test runs 300 cases; `IRAD_FUZZ_CASES=20000 cargo test --release --test cpu scene_fuzz`
//! runs more (and `IRAD_FUZZ_FIRST=N` starts at case N, to reproduce one; `IRAD_FUZZ_SHOW=1`
//! prints why each refused case was refused).

use base64::Engine;
use irad::scene::builtin;
use irad::scene::load::{load_slice, load_slice_with, LoadOptions};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use serde_json::{json, Value};
use std::panic::AssertUnwindSafe;
use std::sync::mpsc;
use std::time::Duration;

/// Time one case may take: loads here take milliseconds.
const BOUND: Duration = Duration::from_secs(10);

/// Numbers a mutation writes: boundaries of glTF's types and of f32.
const INTERESTING: &[f64] = &[
    0.0,
    -1.0,
    1.0,
    2.0,
    3.0,
    4.0,
    5.0,
    6.0,
    0.5,
    255.0,
    65535.0,
    5120.0,
    5121.0,
    5122.0,
    5123.0,
    5125.0,
    5126.0,
    4294967295.0,
    9007199254740993.0,
    1e38,
    -1e38,
    3.4e38,
    1e-38,
    1e6,
    std::f64::consts::PI,
];

fn env(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Paths (as JSON pointers) to every number, array and object in `v`.
fn pointers(v: &Value, at: String, out: &mut Vec<String>) {
    match v {
        Value::Array(a) => {
            out.push(at.clone());
            for (i, x) in a.iter().enumerate() {
                pointers(x, format!("{at}/{i}"), out);
            }
        }
        Value::Object(o) => {
            out.push(at.clone());
            for (k, x) in o {
                if k != "uri" {
                    pointers(x, format!("{at}/{k}"), out);
                }
            }
        }
        Value::Number(_) => out.push(at),
        _ => {}
    }
}

/// One to three JSON-level mutations: a number replaced, an array element duplicated or
/// dropped, an object key removed, a value moved elsewhere.
fn mutate_json(v: &mut Value, r: &mut Pcg64) {
    for _ in 0..r.random_range(1..=3) {
        let mut ps = Vec::new();
        pointers(v, String::new(), &mut ps);
        let p = &ps[r.random_range(0..ps.len())];
        let donor = v.pointer(&ps[r.random_range(0..ps.len())]).cloned();
        let Some(x) = v.pointer_mut(p) else { continue };
        match (x, r.random_range(0..4)) {
            (Value::Number(n), _) => {
                let old = n.as_f64().unwrap_or(0.0);
                let k = r.random_range(0..INTERESTING.len() + 3);
                let new = match k {
                    k if k < INTERESTING.len() => INTERESTING[k],
                    k if k == INTERESTING.len() => old + 1.0,
                    k if k == INTERESTING.len() + 1 => old - 1.0,
                    _ => old * 2.0,
                };
                *n = if new.fract() == 0.0 && new.abs() < 1e18 {
                    serde_json::Number::from(new as i64)
                } else {
                    serde_json::Number::from_f64(new).unwrap_or(0.into())
                };
            }
            (Value::Array(a), 0 | 1) if !a.is_empty() => {
                let i = r.random_range(0..a.len());
                let e = a[i].clone();
                a.push(e);
            }
            (Value::Array(a), 2) if !a.is_empty() => {
                a.remove(r.random_range(0..a.len()));
            }
            (Value::Object(o), 0 | 1) if !o.is_empty() => {
                let k = o.keys().nth(r.random_range(0..o.len())).unwrap().clone();
                o.remove(&k);
            }
            (x, _) => {
                if let Some(d) = donor {
                    *x = d;
                }
            }
        }
    }
}

/// One to four byte-level mutations: flips, 32-bit words overwritten, a cut, an insertion.
fn mutate_bytes(b: &mut Vec<u8>, r: &mut Pcg64) {
    for _ in 0..r.random_range(1..=4) {
        if b.is_empty() {
            return;
        }
        let at = r.random_range(0..b.len());
        match r.random_range(0..5) {
            0 => b[at] ^= 1 << r.random_range(0..8),
            1 => b[at] = r.random(),
            2 => {
                let w = [0u32, 1, 0x7f7f_ffff, 0xffff_ffff, 0x8000_0000, 0x7fc0_0000]
                    [r.random_range(0..6)];
                let end = (at + 4).min(b.len());
                b[at..end].copy_from_slice(&w.to_le_bytes()[..end - at]);
            }
            3 => b.truncate(at),
            _ => b.insert(at, r.random()),
        }
    }
}

/// The built-in scene `name` packed as a .glb (JSON chunk, BIN chunk).
fn glb(name: &str) -> Vec<u8> {
    let mut v: Value = serde_json::from_str(builtin::find(name).unwrap().gltf).unwrap();
    let uri = v["buffers"][0]["uri"].as_str().unwrap().to_string();
    let bin = base64::engine::general_purpose::STANDARD
        .decode(uri.split_once(',').unwrap().1)
        .unwrap();
    v["buffers"][0] = json!({ "byteLength": bin.len() });
    let mut js = v.to_string().into_bytes();
    while !js.len().is_multiple_of(4) {
        js.push(b' ');
    }
    let total = 12 + 8 + js.len() + 8 + bin.len();
    let mut out = b"glTF".to_vec();
    for w in [2, total as u32, js.len() as u32] {
        out.extend_from_slice(&w.to_le_bytes());
    }
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&js);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

/// The cornell box using what the built-ins do not: a sparse accessor (the floor's vertex 0
/// replaced by itself, indices from the floor's index view), a triangle strip and a fan (the
/// back and left walls), and a double-sided light, so that mutations reach those readers.
fn spec_features() -> Value {
    let mut v: Value = serde_json::from_str(builtin::find("cornell").unwrap().gltf).unwrap();
    v["accessors"][0]["sparse"] = json!({
        "count": 1,
        "indices": { "bufferView": 1, "componentType": 5125 },
        "values": { "bufferView": 0 },
    });
    v["meshes"][2]["primitives"][0]["mode"] = json!(5);
    v["meshes"][3]["primitives"][0]["mode"] = json!(6);
    v["materials"][3]["doubleSided"] = json!(true);
    // A 2 x 2 PNG in a data: URI, as base colour (with KHR_texture_transform), emissive
    // texture and alpha MASK, so that mutations reach the texture readers.
    let img = image::RgbaImage::from_raw(2, 2, [255u8, 0, 0, 255, 0, 255, 0, 0].repeat(2)).unwrap();
    let mut png = std::io::Cursor::new(Vec::new());
    img.write_to(&mut png, image::ImageFormat::Png).unwrap();
    let data = base64::engine::general_purpose::STANDARD.encode(png.into_inner());
    v["images"] = json!([{ "uri": format!("data:image/png;base64,{data}") }]);
    v["samplers"] = json!([{ "magFilter": 9728, "wrapS": 33648, "wrapT": 33071 }]);
    v["textures"] = json!([{ "source": 0, "sampler": 0 }]);
    v["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({
        "index": 0, "extensions": { "KHR_texture_transform": { "offset": [0.5, 0.0], "rotation": 1.0, "scale": [2.0, 3.0] } }
    });
    v["materials"][0]["alphaMode"] = json!("MASK");
    v["materials"][3]["emissiveTexture"] = json!({ "index": 0 });
    let mut used = v["extensionsUsed"].as_array().cloned().unwrap_or_default();
    used.push(json!("KHR_texture_transform"));
    v["extensionsUsed"] = json!(used);
    v
}

/// Values a hostile mutation writes as coordinates: past irad's limit (1e9), near f32's end,
/// and infinite.
const HUGE: &[f32] = &[
    1.0e9 + 64.0,
    -1.0e10,
    1.0e15,
    1.0e30,
    -3.4e38,
    f32::INFINITY,
];

/// URIs that name special files, folders, or files outside the scene's folder.
const HOSTILE_URIS: &[&str] = &[
    "/dev/zero",
    "/dev/urandom",
    "/dev/null",
    "/dev/full",
    "/proc/self/status",
    "/etc/passwd",
    "/tmp",
    ".",
    "../outside.bin",
    "../../../../etc/hostname",
    "%2e%2e/%2e%2e/etc/passwd",
    "sub/../../x.bin",
    "%2Fdev%2Fzero",
];

/// One hostile mutation (issue 24) of a seed, then maybe ordinary ones.
fn mutate_hostile(v: &mut Value, r: &mut Pcg64) {
    match r.random_range(0..5) {
        0 => {
            // A node moved far away.
            let n = v["nodes"].as_array().map_or(0, |a| a.len());
            if n > 0 {
                let t: Vec<f32> = (0..3)
                    .map(|_| HUGE[r.random_range(0..HUGE.len())])
                    .collect();
                let t: Vec<Value> = t.iter().map(|&x| json!(x as f64)).collect();
                v["nodes"][r.random_range(0..n)]["translation"] = json!(t);
            }
        }
        1 => {
            // Vertices (or anything else in the buffer) overwritten with huge values.
            let Some(uri) = v["buffers"][0]["uri"].as_str() else {
                return;
            };
            let Some((head, b64)) = uri.split_once(',') else {
                return;
            };
            let engine = &base64::engine::general_purpose::STANDARD;
            let Ok(mut bin) = engine.decode(b64) else {
                return;
            };
            for _ in 0..r.random_range(1..=8) {
                if bin.len() >= 4 {
                    let at = r.random_range(0..bin.len() / 4) * 4;
                    let x = HUGE[r.random_range(0..HUGE.len())];
                    bin[at..at + 4].copy_from_slice(&x.to_le_bytes());
                }
            }
            v["buffers"][0]["uri"] = json!(format!("{head},{}", engine.encode(&bin)));
        }
        2 | 3 => {
            // A buffer's or an image's URI naming a special file or leading out.
            let uri = HOSTILE_URIS[r.random_range(0..HOSTILE_URIS.len())];
            let images = v["images"].as_array().map_or(0, |a| a.len());
            if images > 0 && r.random_bool(0.5) {
                v["images"][r.random_range(0..images)] = json!({ "uri": uri });
            } else {
                v["buffers"][0]["uri"] = json!(uri);
            }
        }
        _ => {
            // An emissive texture black almost everywhere on the floor that faces the camera.
            *v = crate::hostile::floor_emits_where_its_mean_does_not();
            let side = [2u32, 3, 4, 16][r.random_range(0..4)];
            let texels: Vec<[u8; 4]> = (0..side * side)
                .map(|_| match r.random_bool(0.1) {
                    true => [255, 255, 255, 255],
                    false => [0, 0, 0, 255],
                })
                .collect();
            let png = crate::hostile::png(side, side, &texels);
            let data = base64::engine::general_purpose::STANDARD.encode(png);
            v["images"][0]["uri"] = json!(format!("data:image/png;base64,{data}"));
            let filter = [9728, 9729][r.random_range(0..2)];
            v["samplers"][0]["magFilter"] = json!(filter);
        }
    }
    if r.random_bool(0.3) {
        mutate_json(v, r);
    }
}

/// Case `i`: which seed file and which kind of mutation come from `i`; the rest from a PCG
/// stream seeded with `i`. Kinds 4 and 5 are the hostile ones (kind 5 loaded with
/// `allow_outside_paths`).
fn case(i: u64, seeds: &[(&str, Value)], glbs: &[Vec<u8>]) -> Vec<u8> {
    let mut r = Pcg64::seed_from_u64(i);
    match i % 6 {
        0 | 1 => {
            let mut v = seeds[(i / 4) as usize % seeds.len()].1.clone();
            mutate_json(&mut v, &mut r);
            v.to_string().into_bytes()
        }
        4 | 5 => {
            let mut v = seeds[(i / 6) as usize % seeds.len()].1.clone();
            mutate_hostile(&mut v, &mut r);
            v.to_string().into_bytes()
        }
        2 => {
            let mut b = seeds[(i / 4) as usize % seeds.len()]
                .1
                .to_string()
                .into_bytes();
            mutate_bytes(&mut b, &mut r);
            b
        }
        _ => {
            let mut b = glbs[(i / 4) as usize % glbs.len()].clone();
            mutate_bytes(&mut b, &mut r);
            b
        }
    }
}

/// Whether one input loaded, or what went wrong with it; `allow` loads it with
/// `allow_outside_paths`.
fn check(bytes: Vec<u8>, allow: bool) -> Result<bool, String> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let r = std::panic::catch_unwind(AssertUnwindSafe(|| {
            let options = LoadOptions {
                allow_outside_paths: allow,
            };
            let scene = match load_slice_with(&bytes, "fuzz.gltf", "fuzz", None, &options) {
                Ok(s) => s,
                Err(e) => {
                    if std::env::var_os("IRAD_FUZZ_SHOW").is_some() {
                        println!(
                            "refused: {}",
                            e.to_string().chars().take(200).collect::<String>()
                        );
                    }
                    return Ok(false);
                }
            };
            for t in [0.0, scene.duration() * 0.37, scene.duration()] {
                let f = scene.at(t);
                if !f.tris.iter().flatten().all(|p| p.is_finite()) {
                    return Err(format!("loaded, but a vertex at t={t} is not finite"));
                }
                if !f.camera.is_valid() {
                    return Err(format!("loaded, but the camera at t={t} is unusable"));
                }
                if !f.emitters.total_power.is_finite() || !f.areas.iter().all(|a| a.is_finite()) {
                    return Err(format!(
                        "loaded, but power or areas at t={t} are not finite"
                    ));
                }
            }
            // The path tracer on what loaded: finite pixels, no panic.
            let f = scene.at(0.0);
            let tracer = irad::trace::Tracer::new(&f);
            let s = irad::reference::ReferenceSettings {
                width: 4,
                height: 4,
                spp: 2,
                seed: 1,
                ..Default::default()
            };
            let img = irad::reference::render(&f, &tracer, &s, &|| {});
            if !img.data.iter().all(|p| p.is_finite()) {
                return Err("loaded, but the path tracer gives pixels that are not finite".into());
            }
            Ok(true)
        }));
        let _ = tx.send(r.unwrap_or_else(|_| Err("panicked".into())));
    });
    rx.recv_timeout(BOUND)
        .unwrap_or_else(|_| Err(format!("took longer than {BOUND:?}")))
}

#[test]
fn mutated_scene_files_never_panic_hang_or_lie() {
    let mut seeds: Vec<(&str, Value)> = ["cornell-box", "two-rooms", "cornell-light"]
        .iter()
        .map(|&n| {
            (
                n,
                serde_json::from_str(builtin::find(n).unwrap().gltf).unwrap(),
            )
        })
        .collect();
    seeds.push(("cornell-spec", spec_features()));
    // Every seed loads as it is, or its mutations would only test the first refusal.
    for (name, v) in &seeds {
        let s = load_slice(v.to_string().as_bytes(), name, name, None);
        assert!(s.is_ok(), "{name}: {:?}", s.err());
    }
    let glbs = vec![glb("cornell-orbit"), glb("furnace")];
    let first = env("IRAD_FUZZ_FIRST", 0);
    let cases = env("IRAD_FUZZ_CASES", 300);
    let mut failures = Vec::new();
    let mut loaded = 0;
    // Per case kind: [refused, loaded].
    let mut by_kind = [[0u32; 2]; 6];
    let start = std::time::Instant::now();
    for i in first..first + cases {
        match check(case(i, &seeds, &glbs), i % 6 == 5) {
            Ok(l) => {
                loaded += l as usize;
                by_kind[(i % 6) as usize][l as usize] += 1;
            }
            Err(why) => failures.push(format!("case {i}: {why}")),
        }
    }
    println!(
        "{cases} cases from {first} in {:.1} s; [refused, loaded] by kind (json, json, json bytes, glb bytes, hostile, hostile allowed outside): {by_kind:?}",
        start.elapsed().as_secs_f64()
    );
    // Some mutations must still load, or the checks on loaded scenes would test nothing.
    assert!(loaded > 0, "no case loaded");
    assert!(
        cases < 60 || (by_kind[4][1] > 0 && by_kind[4][0] > 0),
        "the hostile kind loads none or refuses none: {by_kind:?}"
    );
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
