//! Hostile files and what the loader and the path tracer do with them (issue 24): an emitter
//! the emitter list misses, special files, files outside the scene's folder.

use crate::scene_files::{lit, load};
use base64::Engine;
use irad::reference::{self, ReferenceSettings};
use irad::scene::load::{load_path, load_path_with, LoadOptions};
use irad::scene::Scene;
use irad::trace::Tracer;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// A PNG of `w x h` RGBA texels (row 0 at the top).
pub(crate) fn png(w: u32, h: u32, texels: &[[u8; 4]]) -> Vec<u8> {
    let img = image::RgbaImage::from_raw(w, h, texels.concat()).unwrap();
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// The lit quad seen from inside (camera at z = 0.9, under the light), its floor emitting
/// through a 2 x 2 nearest-filtered checker (white on the diagonal) repeated 32 times: every
/// point of the 32 x 32 lattice the mean emission is taken at lands on a black texel, so the
/// floor emits at three points in four but is not in the emitter list.
pub(crate) fn floor_emits_where_its_mean_does_not() -> serde_json::Value {
    let (mut g, mut doc) = lit();
    let uv = g.floats(&[0., 0., 32., 0., 32., 32., 0., 32.], "VEC2", 2);
    doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(uv);
    doc["materials"][0]["emissiveFactor"] = json!([1.0, 1.0, 1.0]);
    doc["materials"][0]["emissiveTexture"] = json!({ "index": 0 });
    let (w, b) = ([255, 255, 255, 255], [0, 0, 0, 255]);
    let image = base64::engine::general_purpose::STANDARD.encode(png(2, 2, &[w, b, b, w]));
    doc["images"] = json!([{ "uri": format!("data:image/png;base64,{image}") }]);
    doc["samplers"] = json!([{ "magFilter": 9728 }]);
    doc["textures"] = json!([{ "source": 0, "sampler": 0 }]);
    doc["nodes"][2]["translation"] = json!([0.5, 0.5, 0.9]);
    g.finish(doc)
}

/// Issue 24 item 1: a path that scatters onto an emitting point of a triangle outside the
/// emitter list panicked in `light_pdf` (index u32::MAX). It now counts with MIS weight 1.
#[test]
fn an_emitter_the_emitter_list_misses_does_not_panic_the_reference() {
    let scene = load(&floor_emits_where_its_mean_does_not()).unwrap();
    let f = scene.at(0.0);
    // What makes the case: the floor (triangles 0 and 1) emits at some points, not on average.
    assert_eq!(f.emitters.tris, vec![2, 3], "only the light quad is listed");
    let emitting = (0..64)
        .filter(|k| {
            f.emission_at(0, (*k as f32 + 0.25) / 128.0, 0.3)
                .max_element()
                > 0.0
        })
        .count();
    assert!(emitting > 16, "the floor emits at {emitting} of 64 points");
    let tracer = Tracer::new(&f);
    let s = ReferenceSettings {
        width: 16,
        height: 16,
        spp: 16,
        seed: 3,
        ..Default::default()
    };
    let img = reference::render(&f, &tracer, &s, &|| {});
    let bad = img.data.iter().filter(|p| !p.is_finite()).count();
    assert_eq!(bad, 0, "{bad} pixels not finite");
    // The camera sees the floor's white texels (emission 1) plus light reflected off them.
    let brightest = img.data.iter().map(|p| p.min_element()).fold(0.0, f32::max);
    assert!(brightest > 1.0, "brightest pixel {brightest}");
}

/// Loads a scene file, failing the test if loading takes more than 10 s.
fn load_file(path: &Path) -> Result<Scene, String> {
    load_file_with(path, false)
}

/// [`load_file`], reading files outside the scene's folder when `outside`.
fn load_file_with(path: &Path, outside: bool) -> Result<Scene, String> {
    let start = Instant::now();
    let (tx, rx) = std::sync::mpsc::channel();
    let path = path.to_path_buf();
    std::thread::spawn(move || {
        let options = LoadOptions {
            allow_outside_paths: outside,
        };
        let _ = tx.send(load_path_with(&path, &options).map_err(|e| e.to_string()));
    });
    let r = rx
        .recv_timeout(Duration::from_secs(10))
        .expect("loading hung (or panicked)");
    assert!(start.elapsed() < Duration::from_secs(10));
    r
}

/// A fresh folder for one test's files.
fn folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("irad-hostile-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The lit quad with its buffer in a file `bin` beside it, as (document, buffer bytes).
fn lit_with_external_buffer() -> (serde_json::Value, Vec<u8>) {
    let (g, doc) = lit();
    let doc = g.finish(doc);
    let uri = doc["buffers"][0]["uri"].as_str().unwrap().to_string();
    let bin = base64::engine::general_purpose::STANDARD
        .decode(uri.split_once(',').unwrap().1)
        .unwrap();
    (doc, bin)
}

/// Issue 24 item 2: a buffer URI or a scene path naming /dev/zero grew past 4 GB in 10 s.
/// Both are refused at once, naming the file, because it is not a regular file.
#[test]
fn dev_zero_as_buffer_or_scene_is_refused_at_once() {
    let dir = folder("dev-zero");
    let (mut doc, _) = lit_with_external_buffer();
    doc["buffers"][0]["uri"] = json!("/dev/zero");
    let path = dir.join("zero.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    // Refused as outside the folder by default; allowed, as not a regular file.
    let e = load_file_with(&path, true).unwrap_err();
    assert!(e.contains("zero.gltf") && e.contains("/dev/zero"), "{e}");
    assert!(e.contains("not a regular file"), "{e}");
    let e = load_path(Path::new("/dev/zero")).unwrap_err().to_string();
    assert!(
        e.starts_with("/dev/zero: ") && e.contains("not a regular file"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A buffer file longer than its `byteLength` loads (only the declared bytes are read), and
/// one shorter is refused as short.
#[test]
fn a_buffer_file_is_read_up_to_its_byte_length() {
    let dir = folder("byte-length");
    let (mut doc, mut bin) = lit_with_external_buffer();
    let declared = bin.len();
    doc["buffers"][0]["uri"] = json!("lit.bin");
    let path = dir.join("lit.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    bin.extend(std::iter::repeat_n(0xffu8, 1 << 20));
    std::fs::write(dir.join("lit.bin"), &bin).unwrap();
    assert_eq!(load_file(&path).unwrap().at(0.0).tris.len(), 4);
    std::fs::write(dir.join("lit.bin"), &bin[..declared - 4]).unwrap();
    let e = load_file(&path).unwrap_err();
    assert!(e.contains("buffer 0 is short"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 24 item 3: buffer and image URIs that are absolute or lead out of the scene's folder
/// (by `..` or a symbolic link) are refused, naming the URI, the scene file and the option;
/// allowed, they load.
#[test]
fn files_outside_the_scene_folder_are_refused_unless_allowed() {
    let top = folder("outside");
    let dir = top.join("scene");
    std::fs::create_dir_all(&dir).unwrap();
    let (mut doc, bin) = lit_with_external_buffer();
    std::fs::write(top.join("outside.bin"), &bin).unwrap();
    std::os::unix::fs::symlink(top.join("outside.bin"), dir.join("link.bin")).unwrap();
    let path = dir.join("s.gltf");
    let outside = top.join("outside.bin").display().to_string();
    for uri in [
        "/etc/passwd",
        "../outside.bin",
        "link.bin",
        outside.as_str(),
    ] {
        doc["buffers"][0]["uri"] = json!(uri);
        std::fs::write(&path, doc.to_string()).unwrap();
        let e = load_file(&path).unwrap_err();
        assert!(
            e.starts_with(&format!("{}: buffer 0 refers to '{uri}'", path.display())),
            "{e}"
        );
        assert!(e.contains("`allow_outside_paths`"), "{e}");
        if uri != "/etc/passwd" {
            assert_eq!(
                load_file_with(&path, true).unwrap().at(0.0).tris.len(),
                4,
                "{uri}"
            );
        }
    }
    // A file inside the folder, and one reached by `..` that stays inside, load.
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    std::fs::write(dir.join("in.bin"), &bin).unwrap();
    doc["buffers"][0]["uri"] = json!("sub/../in.bin");
    std::fs::write(&path, doc.to_string()).unwrap();
    assert_eq!(load_file(&path).unwrap().at(0.0).tris.len(), 4);
    // An image outside is refused too (an error, not a warning with the texture dropped).
    doc["buffers"][0]["uri"] = json!("in.bin");
    doc["images"] = json!([{ "uri": "../picture.png" }]);
    std::fs::write(top.join("picture.png"), png(1, 1, &[[9, 9, 9, 255]])).unwrap();
    std::fs::write(&path, doc.to_string()).unwrap();
    let e = load_file(&path).unwrap_err();
    assert!(e.contains("image 0 refers to '../picture.png'"), "{e}");
    assert!(load_file_with(&path, true).is_ok());
    std::fs::remove_dir_all(&top).unwrap();
}

/// A buffer file that is not geometry (text here) is refused without its bytes in the
/// message: the loader once printed them back as vertex coordinates.
#[test]
fn a_malformed_buffer_is_refused_without_echoing_its_bytes() {
    let dir = folder("echo");
    let (mut doc, bin) = lit_with_external_buffer();
    let text: Vec<u8> = b"root:x:0:0:secret-password-here:/root:/bin/bash\n"
        .iter()
        .copied()
        .cycle()
        .take(bin.len())
        .collect();
    std::fs::write(dir.join("text.bin"), &text).unwrap();
    doc["buffers"][0]["uri"] = json!("text.bin");
    let path = dir.join("s.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    let e = load_file(&path).unwrap_err();
    assert!(e.contains("mesh 0"), "{e}");
    let floats: &[f32] = bytemuck::cast_slice(&text[..48]);
    for x in floats {
        for shown in [format!("{x}"), format!("{x:e}"), format!("{:.3e}", x)] {
            assert!(!e.contains(&shown), "{shown} (the file's bytes) in: {e}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 24 item 8: a write that fails (a full disk: the temporary file is made a link to
/// /dev/full) names the file and the OS's error once, not "Format error decoding OpenExr".
#[test]
fn a_full_disk_names_the_file_and_the_os_error_once() {
    let dir = folder("full");
    let path = dir.join("frame_0000.exr");
    let tmp = dir.join(format!(".frame_0000.exr.tmp-{}.exr", std::process::id()));
    std::os::unix::fs::symlink("/dev/full", &tmp).unwrap();
    let img = irad::image::Hdr::new(64, 64);
    let e = format!("{:#}", img.write_exr(&path).unwrap_err());
    assert!(e.starts_with(&path.display().to_string()), "{e}");
    assert_eq!(e.matches("No space left on device").count(), 1, "{e}");
    assert!(!e.contains("Format error"), "{e}");
    // Nothing is left: neither the file nor the temporary.
    assert!(!path.exists() && std::fs::symlink_metadata(&tmp).is_err());
    std::fs::remove_dir_all(&dir).unwrap();
}
