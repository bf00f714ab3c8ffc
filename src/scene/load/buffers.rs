//! Buffers, buffer views and accessors: load the bytes and check that every view and accessor
//! lies inside them, so that reading can never go past the data.

use super::{Ctx, LoadError};
use std::path::Path;

/// The bytes of every buffer, by index.
pub(super) type Buffers = Vec<gltf::buffer::Data>;

/// Loads every buffer (embedded, external or the .glb's BIN chunk) and checks views and
/// accessors against them.
pub(super) fn load(
    cx: &Ctx,
    doc: &gltf::Document,
    base: Option<&Path>,
    blob: Option<Vec<u8>>,
) -> Result<Buffers, LoadError> {
    let base = base.unwrap_or(Path::new("."));
    check_external(cx, doc, base)?;
    let buffers = gltf::import_buffers(doc, Some(base), blob).map_err(|e| match e {
        gltf::Error::BufferLength {
            buffer,
            expected,
            actual,
        } => cx.err(format!(
            "buffer {buffer} is short: it declares {expected} bytes but holds {actual}"
        )),
        gltf::Error::Io(io) => cx.err(format!("a buffer cannot be read: {io}")),
        gltf::Error::MissingBlob => cx.err("the .glb has no BIN chunk but a buffer refers to it"),
        other => cx.err(format!("a buffer cannot be loaded: {other}")),
    })?;
    check_views(cx, doc, &buffers)?;
    check_accessors(cx, doc)?;
    Ok(buffers)
}

/// Every external buffer file exists, so the message can name it.
fn check_external(cx: &Ctx, doc: &gltf::Document, base: &Path) -> Result<(), LoadError> {
    for buf in doc.buffers() {
        if let gltf::buffer::Source::Uri(uri) = buf.source() {
            if !uri.starts_with("data:") {
                let full = base.join(uri);
                if let Err(e) = std::fs::metadata(&full) {
                    return Err(cx.err(format!(
                        "buffer {} refers to '{uri}' ({}), which cannot be read: {e}",
                        buf.index(),
                        full.display()
                    )));
                }
            }
        }
    }
    Ok(())
}

fn check_views(cx: &Ctx, doc: &gltf::Document, buffers: &Buffers) -> Result<(), LoadError> {
    for view in doc.views() {
        let len = buffers[view.buffer().index()].len();
        if view.offset() + view.length() > len {
            return Err(cx.err(format!(
                "bufferView {} spans bytes {}..{} of buffer {} which holds {len}",
                view.index(),
                view.offset(),
                view.offset() + view.length(),
                view.buffer().index()
            )));
        }
    }
    Ok(())
}

fn check_accessors(cx: &Ctx, doc: &gltf::Document) -> Result<(), LoadError> {
    for acc in doc.accessors() {
        if acc.sparse().is_some() {
            return Err(cx.err(format!(
                "accessor {} is sparse, which irad does not read",
                acc.index()
            )));
        }
        let Some(view) = acc.view() else { continue };
        let elem = acc.size();
        let stride = view.stride().unwrap_or(elem);
        let need = if acc.count() == 0 {
            0
        } else {
            acc.offset() + stride * (acc.count() - 1) + elem
        };
        if need > view.length() {
            return Err(cx.err(format!(
                "accessor {} needs {need} bytes of bufferView {} which has {}",
                acc.index(),
                view.index(),
                view.length()
            )));
        }
    }
    Ok(())
}
