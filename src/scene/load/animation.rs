//! Animations: channels of translation, rotation and scale keys on nodes.

use super::buffers::Buffers;
use super::{Ctx, LoadError};
use crate::scene::{anim, Local, Node};
use glam::{Vec3, Vec4};
use gltf::animation::util::ReadOutputs;

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
    let reader = c.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let Some(times) = reader.read_inputs() else {
        return Err(cx.err(format!(
            "animation {} has a channel without key times",
            a.index()
        )));
    };
    let times: Vec<f32> = times.collect();
    if times.is_empty()
        || times.iter().any(|t| !t.is_finite())
        || times.windows(2).any(|w| w[1] < w[0])
    {
        return Err(cx.err(format!(
            "animation {} has key times that are empty, non-finite or not increasing",
            a.index()
        )));
    }
    let Some((property, values)) = outputs(cx, a, reader.read_outputs())? else {
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
    if values.len() != times.len() * per_key || values.iter().any(|v| !v.is_finite()) {
        return Err(cx.err(format!(
            "animation {} has {} values for {} keys (needs {} finite values)",
            a.index(),
            values.len(),
            times.len(),
            times.len() * per_key
        )));
    }
    Ok(Some(anim::Channel {
        node: c.target().node().index(),
        property,
        interpolation,
        times,
        values,
    }))
}

/// The channel's key values as Vec4s, or None for morph-target weights (ignored).
fn outputs(
    cx: &mut Ctx,
    a: &gltf::Animation,
    outputs: Option<ReadOutputs>,
) -> Result<Option<(anim::Property, Vec<Vec4>)>, LoadError> {
    Ok(Some(match outputs {
        Some(ReadOutputs::Translations(v)) => (
            anim::Property::Translation,
            v.map(|x| Vec3::from(x).extend(0.0)).collect(),
        ),
        Some(ReadOutputs::Scales(v)) => (
            anim::Property::Scale,
            v.map(|x| Vec3::from(x).extend(0.0)).collect(),
        ),
        Some(ReadOutputs::Rotations(r)) => (
            anim::Property::Rotation,
            r.into_f32().map(Vec4::from).collect(),
        ),
        Some(ReadOutputs::MorphTargetWeights(_)) => {
            cx.warn("morph-target weight animations are ignored");
            return Ok(None);
        }
        None => {
            return Err(cx.err(format!(
                "animation {} has a channel without values",
                a.index()
            )))
        }
    }))
}
