//! Every file the loader reads, read here: the scene file itself, and the buffers and images
//! its URIs name. Only regular files are read (a device such as `/dev/zero`, a pipe or a
//! folder is refused before it is opened), and never more than is needed: a buffer at most
//! its declared `byteLength`, an image or a scene file at most a fixed cap. A URI is read
//! only from the scene's folder and below (after symbolic links are resolved) unless the
//! caller allows more ([`LoadOptions::allow_outside_paths`]).

use base64::Engine;
use std::io::Read;
use std::path::{Path, PathBuf};

/// The largest scene file (.gltf or .glb) irad reads.
pub const MAX_SCENE_BYTES: u64 = 2 << 30;

/// The largest image file irad reads (a texture is at most 8192 texels on a side anyway).
pub const MAX_IMAGE_BYTES: u64 = 1 << 28;

/// How the loader treats the files a scene names.
#[derive(Clone, Copy, Debug, Default)]
pub struct LoadOptions {
    /// Read buffer and image URIs that are absolute or lead out of the scene file's folder
    /// (`..`, or a symbolic link to elsewhere). Off by default: a scene file from elsewhere
    /// then reads nothing but its own folder.
    pub allow_outside_paths: bool,
}

/// Reads at most `limit` bytes of the regular file at `path`; a longer file, a missing one,
/// or one that is not a regular file is an error saying so (without its contents).
pub fn read_regular(path: &Path, limit: u64) -> Result<Vec<u8>, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot be read: {e}"))?;
    if !meta.is_file() {
        return Err(format!(
            "is not a regular file ({}), so irad does not read it",
            kind(&meta)
        ));
    }
    let file = std::fs::File::open(path).map_err(|e| format!("cannot be read: {e}"))?;
    let mut data = Vec::with_capacity(meta.len().min(limit) as usize);
    file.take(limit)
        .read_to_end(&mut data)
        .map_err(|e| format!("cannot be read: {e}"))?;
    Ok(data)
}

/// Reads a whole scene file, refusing one over [`MAX_SCENE_BYTES`].
pub fn read_scene(path: &Path) -> Result<Vec<u8>, String> {
    let data = read_regular(path, MAX_SCENE_BYTES + 1)?;
    if data.len() as u64 > MAX_SCENE_BYTES {
        return Err(format!(
            "is larger than {} GiB, irad's limit for a scene file",
            MAX_SCENE_BYTES >> 30
        ));
    }
    Ok(data)
}

/// What a file that is not a regular one is.
fn kind(meta: &std::fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_fifo() {
            return "a pipe";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if meta.is_dir() {
        "a folder"
    } else {
        "not a plain file"
    }
}

/// The bytes of a `data:` URI (base64; padding optional), or None for any other URI.
pub(super) fn data_uri(uri: &str) -> Option<Result<Vec<u8>, String>> {
    let rest = uri.strip_prefix("data:")?;
    let Some((_, b64)) = rest.split_once(";base64,") else {
        return Some(Err("has a data: URI that is not base64".into()));
    };
    let engine = base64::engine::GeneralPurpose::new(
        &base64::alphabet::STANDARD,
        base64::engine::GeneralPurposeConfig::new()
            .with_decode_padding_mode(base64::engine::DecodePaddingMode::Indifferent),
    );
    Some(
        engine
            .decode(b64.trim())
            .map_err(|e| format!("has a data: URI that is not base64 ({e})")),
    )
}

/// The file a URI that is not a `data:` URI names: relative to `base`, percent-decoded.
/// The error says what is wrong with the URI, for a message that starts with what names it
/// ("buffer 2 ").
pub(super) fn resolve(base: &Path, uri: &str) -> Result<PathBuf, String> {
    if uri.contains(':') {
        return Err(format!(
            "refers to '{uri}': irad reads embedded data: URIs and relative file paths only"
        ));
    }
    let decoded = urlencoding::decode(uri)
        .map_err(|e| format!("has the URI '{uri}', which does not percent-decode to UTF-8: {e}"))?;
    Ok(base.join(&*decoded))
}

/// Whether the file a (relative, percent-encoded) URI `uri` names lies in `base` (the
/// scene's folder) or below once symbolic links are resolved; an error saying where it leads
/// if not, unless `options` allow that. A file that does not exist passes here when its path
/// stays inside (reading it then says it is missing).
pub(super) fn check_inside(base: &Path, uri: &str, options: &LoadOptions) -> Result<(), String> {
    if options.allow_outside_paths {
        return Ok(());
    }
    let base = if base.as_os_str().is_empty() {
        Path::new(".")
    } else {
        base
    };
    let outside = |where_: String| {
        format!(
            "refers to '{uri}', {where_}: irad reads only files in the scene's folder and below unless `allow_outside_paths` is set"
        )
    };
    let decoded = PathBuf::from(&*urlencoding::decode(uri).unwrap_or_default());
    let path = base.join(&decoded);
    if decoded.is_absolute() || decoded.has_root() {
        return Err(outside("an absolute path".into()));
    }
    let (Ok(root), Ok(full)) = (base.canonicalize(), path.canonicalize()) else {
        // Nothing to read there: the read says so. A path that climbs out is refused even so.
        return match lexically_outside(&decoded) {
            true => Err(outside("outside the scene's folder".into())),
            false => Ok(()),
        };
    };
    if full.starts_with(&root) {
        Ok(())
    } else {
        Err(outside(format!(
            "which leads to {}, outside the scene's folder {}",
            full.display(),
            root.display()
        )))
    }
}

/// Whether a relative path climbs above its start by its `..` alone.
fn lexically_outside(p: &Path) -> bool {
    let mut depth = 0i64;
    for c in p.components() {
        match c {
            std::path::Component::ParentDir => depth -= 1,
            std::path::Component::Normal(_) => depth += 1,
            _ => {}
        }
        if depth < 0 {
            return true;
        }
    }
    false
}
