//! The one embedded buffer every test's glTF document holds: its bytes, buffer views and
//! accessors, appended to by [`view`], [`accessor`] and [`positions`] (the document builders of the
//! test modules keep the three vectors and call these).

use serde_json::{json, Value};

/// Appends `bytes` (4-byte aligned) as a buffer view and an accessor of `count` elements of
/// type `ty` ("SCALAR", "VEC3", ...) and component type `component` (5126 float, 5125 u32,
/// ...); returns the accessor's index.
pub fn accessor(
    bin: &mut Vec<u8>,
    views: &mut Vec<Value>,
    accessors: &mut Vec<Value>,
    (bytes, count, ty, component): (&[u8], usize, &str, u32),
) -> usize {
    let v = view(bin, views, bytes);
    accessors.push(json!({
        "bufferView": v, "count": count, "type": ty, "componentType": component,
    }));
    accessors.len() - 1
}

/// Appends `bytes` (4-byte aligned) as a buffer view (an image's, or an accessor's);
/// returns the view's index.
pub fn view(bin: &mut Vec<u8>, views: &mut Vec<Value>, bytes: &[u8]) -> usize {
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    views.push(json!({ "buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len() }));
    bin.extend_from_slice(bytes);
    views.len() - 1
}

/// Appends positions as a VEC3 float accessor with the min and max glTF requires.
pub fn positions(
    bin: &mut Vec<u8>,
    views: &mut Vec<Value>,
    accessors: &mut Vec<Value>,
    p: &[[f32; 3]],
) -> usize {
    let bytes: &[u8] = bytemuck::cast_slice(p.as_flattened());
    let acc = accessor(bin, views, accessors, (bytes, p.len(), "VEC3", 5126));
    let lo = p
        .iter()
        .fold([f32::MAX; 3], |a, v| [0, 1, 2].map(|i| a[i].min(v[i])));
    let hi = p
        .iter()
        .fold([f32::MIN; 3], |a, v| [0, 1, 2].map(|i| a[i].max(v[i])));
    accessors[acc]["min"] = json!(lo);
    accessors[acc]["max"] = json!(hi);
    acc
}
