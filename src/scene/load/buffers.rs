//! Buffers, buffer views and accessors: load the bytes, check that every view lies inside its
//! buffer, and read accessors (dense or sparse, any component type) with every offset checked,
//! so that no file can make reading go past the data or panic.

use super::{files, Ctx, LoadError};
use gltf::accessor::{DataType, Dimensions};
use std::path::Path;

/// The bytes of every buffer, by index.
pub(super) type Buffers = Vec<gltf::buffer::Data>;

/// The most elements an accessor without a bufferView (all zeros, maybe sparse) may declare:
/// such an accessor costs memory without costing file size.
const MAX_VIEWLESS: usize = 1 << 22;

/// Loads every buffer (embedded, external or the .glb's BIN chunk) and checks the views. An
/// external buffer is read through [`super::files`]: a regular file, at most its declared
/// `byteLength`.
pub(super) fn load(
    cx: &Ctx,
    doc: &gltf::Document,
    base: Option<&Path>,
    mut blob: Option<Vec<u8>>,
) -> Result<Buffers, LoadError> {
    let base = base.unwrap_or(Path::new("."));
    let mut buffers = Vec::new();
    for buf in doc.buffers() {
        let what = format!("buffer {}", buf.index());
        let declared = buf.length();
        let mut data = match buf.source() {
            gltf::buffer::Source::Bin => blob
                .take()
                .ok_or_else(|| cx.err("the .glb has no BIN chunk but a buffer refers to it"))?,
            gltf::buffer::Source::Uri(uri) => match files::data_uri(uri) {
                Some(d) => d.map_err(|e| cx.err(format!("{what} {e}")))?,
                None => {
                    let path = files::resolve(base, uri)
                        .and_then(|p| files::check_inside(base, uri, &cx.options).map(|_| p))
                        .map_err(|e| cx.err(format!("{what} {e}")))?;
                    files::read_regular(&path, declared as u64).map_err(|e| {
                        cx.err(format!(
                            "{what} refers to '{uri}' ({}), which {e}",
                            path.display()
                        ))
                    })?
                }
            },
        };
        if data.len() < declared {
            return Err(cx.err(format!(
                "{what} is short: it declares {declared} bytes but holds {}",
                data.len()
            )));
        }
        while !data.len().is_multiple_of(4) {
            data.push(0);
        }
        buffers.push(gltf::buffer::Data(data));
    }
    check_views(cx, doc, &buffers)?;
    Ok(buffers)
}

fn check_views(cx: &Ctx, doc: &gltf::Document, buffers: &Buffers) -> Result<(), LoadError> {
    for view in doc.views() {
        let len = buffers[view.buffer().index()].len();
        let end = view.offset().checked_add(view.length());
        if end.is_none_or(|end| end > len) {
            return Err(cx.err(format!(
                "bufferView {} spans bytes {}..{} of buffer {} which holds {len}",
                view.index(),
                view.offset(),
                view.offset() as u128 + view.length() as u128,
                view.buffer().index()
            )));
        }
    }
    Ok(())
}

/// Components per element of an accessor type.
pub(super) fn width(d: Dimensions) -> usize {
    d.multiplicity()
}

/// One component as f32: floats as they are, integers normalized to [0,1] or [-1,1] when
/// the accessor says so (glTF 2.0 section 3.11), else converted.
fn component(t: DataType, normalized: bool, b: &[u8]) -> f32 {
    match (t, normalized) {
        (DataType::F32, _) => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        (DataType::U8, false) => b[0] as f32,
        (DataType::U8, true) => b[0] as f32 / 255.0,
        (DataType::I8, false) => b[0] as i8 as f32,
        (DataType::I8, true) => (b[0] as i8 as f32 / 127.0).max(-1.0),
        (DataType::U16, false) => u16::from_le_bytes([b[0], b[1]]) as f32,
        (DataType::U16, true) => u16::from_le_bytes([b[0], b[1]]) as f32 / 65535.0,
        (DataType::I16, false) => i16::from_le_bytes([b[0], b[1]]) as f32,
        (DataType::I16, true) => (i16::from_le_bytes([b[0], b[1]]) as f32 / 32767.0).max(-1.0),
        (DataType::U32, _) => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
    }
}

/// One unsigned integer component (for indices).
fn unsigned(t: DataType, b: &[u8]) -> Option<u32> {
    match t {
        DataType::U8 => Some(b[0] as u32),
        DataType::U16 => Some(u16::from_le_bytes([b[0], b[1]]) as u32),
        DataType::U32 => Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        _ => None,
    }
}

/// The bytes of `count` elements of `elem` bytes at `offset` into `view`, `stride` apart
/// (0: packed), checked against the view; `what` names them in the message.
fn strided<'b>(
    cx: &Ctx,
    buffers: &'b Buffers,
    view: &gltf::buffer::View,
    offset: usize,
    count: usize,
    elem: usize,
    what: &str,
) -> Result<(&'b [u8], usize), LoadError> {
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        return Err(cx.err(format!(
            "{what}: bufferView {} has byteStride {stride}, less than the {elem}-byte element",
            view.index()
        )));
    }
    let need = match count {
        0 => Some(0),
        n => stride
            .checked_mul(n - 1)
            .and_then(|x| x.checked_add(elem))
            .and_then(|x| x.checked_add(offset)),
    };
    let data = &buffers[view.buffer().index()][view.offset()..view.offset() + view.length()];
    match need {
        Some(need) if need <= data.len() => Ok((&data[offset.min(data.len())..], stride)),
        _ => Err(cx.err(format!(
            "{what}: {count} elements of {elem} bytes, {stride} apart, from byte {offset} do not fit in bufferView {} which has {} bytes",
            view.index(),
            view.length()
        ))),
    }
}

/// An accessor read as flat f32 components (`width(acc.dimensions())` per element), sparse
/// substitutions applied. `what` says what it is used for, for messages.
pub(super) fn floats(
    cx: &Ctx,
    buffers: &Buffers,
    acc: &gltf::Accessor,
    what: &str,
) -> Result<Vec<f32>, LoadError> {
    let what = format!("accessor {} ({what})", acc.index());
    let (t, norm, w) = (acc.data_type(), acc.normalized(), width(acc.dimensions()));
    let cs = t.size();
    let mut out = match acc.view() {
        Some(view) => {
            let (data, stride) =
                strided(cx, buffers, &view, acc.offset(), acc.count(), cs * w, &what)?;
            let mut out = Vec::with_capacity(acc.count() * w);
            for i in 0..acc.count() {
                for c in 0..w {
                    out.push(component(t, norm, &data[i * stride + c * cs..]));
                }
            }
            out
        }
        None if acc.count() <= MAX_VIEWLESS => vec![0.0; acc.count() * w],
        None => return Err(viewless(cx, acc, &what)),
    };
    if let Some(sparse) = acc.sparse() {
        let at = sparse_indices(cx, buffers, acc, &sparse, &what)?;
        let vals = sparse.values();
        let (data, stride) = strided(
            cx,
            buffers,
            &vals.view(),
            vals.offset(),
            at.len(),
            cs * w,
            &what,
        )?;
        for (k, &i) in at.iter().enumerate() {
            for c in 0..w {
                out[i as usize * w + c] = component(t, norm, &data[k * stride + c * cs..]);
            }
        }
    }
    Ok(out)
}

fn viewless(cx: &Ctx, acc: &gltf::Accessor, what: &str) -> LoadError {
    cx.err(format!(
        "{what} has no bufferView and {} elements; irad allows at most {MAX_VIEWLESS} such",
        acc.count()
    ))
}

/// A sparse accessor's indices: strictly increasing and inside the accessor.
fn sparse_indices(
    cx: &Ctx,
    buffers: &Buffers,
    acc: &gltf::Accessor,
    sparse: &gltf::accessor::sparse::Sparse,
    what: &str,
) -> Result<Vec<u32>, LoadError> {
    let idx = sparse.indices();
    let t = match idx.index_type() {
        gltf::accessor::sparse::IndexType::U8 => DataType::U8,
        gltf::accessor::sparse::IndexType::U16 => DataType::U16,
        gltf::accessor::sparse::IndexType::U32 => DataType::U32,
    };
    let n = sparse.count();
    let (data, stride) = strided(cx, buffers, &idx.view(), idx.offset(), n, t.size(), what)?;
    let at: Vec<u32> = (0..n)
        .filter_map(|k| unsigned(t, &data[k * stride..]))
        .collect();
    let increasing = at.windows(2).all(|w| w[0] < w[1]);
    if !increasing || at.last().is_some_and(|&i| i as usize >= acc.count()) {
        return Err(cx.err(format!(
            "{what}: its sparse indices must increase strictly and stay below its count {}",
            acc.count()
        )));
    }
    Ok(at)
}

/// An accessor read as vertex indices: it must hold unsigned bytes, shorts or ints.
pub(super) fn indices(
    cx: &Ctx,
    buffers: &Buffers,
    acc: &gltf::Accessor,
    what: &str,
) -> Result<Vec<u32>, LoadError> {
    let t = acc.data_type();
    if acc.dimensions() != Dimensions::Scalar
        || !matches!(t, DataType::U8 | DataType::U16 | DataType::U32)
        || acc.normalized()
    {
        return Err(cx.err(format!(
            "accessor {} ({what}) holds {:?} {:?}{}; indices must be unsigned byte, short or int scalars",
            acc.index(),
            t,
            acc.dimensions(),
            if acc.normalized() { " (normalized)" } else { "" }
        )));
    }
    // Dense indices are read as integers; sparse or view-less ones go through f32 (exact up
    // to 2^24).
    if acc.sparse().is_none() {
        if let Some(view) = acc.view() {
            let w = format!("accessor {} ({what})", acc.index());
            let (data, stride) =
                strided(cx, buffers, &view, acc.offset(), acc.count(), t.size(), &w)?;
            return Ok((0..acc.count())
                .filter_map(|i| unsigned(t, &data[i * stride..]))
                .collect());
        }
    }
    Ok(floats(cx, buffers, acc, what)?
        .into_iter()
        .map(|x| x as u32)
        .collect())
}
