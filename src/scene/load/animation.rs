//! Animations: channels of translation, rotation and scale keys on nodes.

use super::buffers::{self, Buffers};
use super::{Ctx, LoadError, MAX_COORD};
use crate::scene::{anim, Local, Node};
use glam::{Vec3, Vec4};
use gltf::accessor::Dimensions;

/// The latest key time irad accepts (seconds): about 11.6 days.
const MAX_TIME: f32 = 1e6;

/// Every channel of every animation; an animated node given by a matrix becomes TRS.
pub(super) fn read(
    cx: &mut Ctx,
    doc: &gltf::Document,
    buffers: &Buffers,
    nodes: &mut [Node],
) -> Result<Vec<anim::Channel>, LoadError> {
    let mut channels = Vec::new();
    for a in doc.animations() {
        for c in a.channels() {
            let Some(ch) = channel(cx, &a, &c, buffers)? else {
                continue;
            };
            if let Local::Matrix(m) = nodes[ch.node].local {
                cx.warn("an animated node had a matrix; it was decomposed into TRS");
                let (s, r, t) = m.to_scale_rotation_translation();
                nodes[ch.node].local = Local::Trs {
                    translation: t,
                    rotation: r,
                    scale: s,
                };
            }
            channels.push(ch);
        }
    }
    Ok(channels)
}

/// One channel, or None for a kind irad ignores (morph-target weights).
fn channel(
    cx: &mut Ctx,
    a: &gltf::Animation,
    c: &gltf::animation::Channel,
    buffers: &Buffers,
) -> Result<Option<anim::Channel>, LoadError> {
    let what = format!("key times of animation {}", a.index());
    let input = c.sampler().input();
    if input.dimensions() != Dimensions::Scalar {
        return Err(cx.err(format!("accessor {} ({what}) is not SCALAR", input.index())));
    }
    let times = buffers::floats(cx, buffers, &input, &what)?;
    if times.is_empty()
        || times.iter().any(|t| !t.is_finite() || t.abs() > MAX_TIME)
        || times.windows(2).any(|w| w[1] < w[0])
    {
        return Err(cx.err(format!(
            "animation {} has key times that are empty, non-finite, beyond {MAX_TIME:e} s or not increasing",
            a.index()
        )));
    }
    let Some((property, values)) = outputs(cx, a, c, buffers)? else {
        return Ok(None);
    };
    let interpolation = match c.sampler().interpolation() {
        gltf::animation::Interpolation::Step => anim::Interpolation::Step,
        gltf::animation::Interpolation::Linear => anim::Interpolation::Linear,
        gltf::animation::Interpolation::CubicSpline => anim::Interpolation::CubicSpline,
    };
    let per_key = if interpolation == anim::Interpolation::CubicSpline {
        3
    } else {
        1
    };
    if values.len() != times.len() * per_key
        || values
            .iter()
            .any(|v| !v.is_finite() || v.abs().max_element() > MAX_COORD)
    {
        return Err(cx.err(format!(
            "animation {} has {} values for {} keys (needs {} finite values, each within {MAX_COORD:e})",
            a.index(),
            values.len(),
            times.len(),
            times.len() * per_key
        )));
    }
    check_rotations(cx, a, property, interpolation, &values)?;
    Ok(Some(anim::Channel {
        node: c.target().node().index(),
        property,
        interpolation,
        times,
        values,
    }))
}

/// Rotation keys are quaternions of non-zero length (tangents may be zero).
fn check_rotations(
    cx: &Ctx,
    a: &gltf::Animation,
    property: anim::Property,
    interpolation: anim::Interpolation,
    values: &[Vec4],
) -> Result<(), LoadError> {
    if property != anim::Property::Rotation {
        return Ok(());
    }
    let keys: Vec<&Vec4> = match interpolation {
        anim::Interpolation::CubicSpline => values.iter().skip(1).step_by(3).collect(),
        _ => values.iter().collect(),
    };
    if let Some(k) = keys.iter().position(|q| q.length_squared() < 1e-12) {
        return Err(cx.err(format!(
            "animation {} has a zero quaternion as rotation key {k}, which is no rotation",
            a.index()
        )));
    }
    Ok(())
}

/// The channel's key values as Vec4s, or None for morph-target weights (ignored).
fn outputs(
    cx: &mut Ctx,
    a: &gltf::Animation,
    c: &gltf::animation::Channel,
    buffers: &Buffers,
) -> Result<Option<(anim::Property, Vec<Vec4>)>, LoadError> {
    let (property, dims) = match c.target().property() {
        gltf::animation::Property::Translation => (anim::Property::Translation, Dimensions::Vec3),
        gltf::animation::Property::Scale => (anim::Property::Scale, Dimensions::Vec3),
        gltf::animation::Property::Rotation => (anim::Property::Rotation, Dimensions::Vec4),
        gltf::animation::Property::MorphTargetWeights => {
            cx.warn("morph-target weight animations are ignored");
            return Ok(None);
        }
    };
    let acc = c.sampler().output();
    let what = format!("values of animation {}", a.index());
    if acc.dimensions() != dims {
        return Err(cx.err(format!(
            "accessor {} ({what}) is {:?}, but a {:?} channel needs {dims:?}",
            acc.index(),
            acc.dimensions(),
            property
        )));
    }
    let flat = buffers::floats(cx, buffers, &acc, &what)?;
    let values = match dims {
        Dimensions::Vec3 => flat
            .chunks_exact(3)
            .map(|x| Vec3::from_slice(x).extend(0.0))
            .collect(),
        _ => flat.chunks_exact(4).map(Vec4::from_slice).collect(),
    };
    Ok(Some((property, values)))
}
