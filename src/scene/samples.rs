//! Emitter samples for direct light: points on the emitting triangles, stratified over their
//! power, and the punctual lights, each as the samples its shadow maps need.

use super::{Frame, LightKind, PunctualLight};
use glam::Vec3;

/// A point sample on the emitters for direct light: position, unit normal (the emitting
/// side) and `Le / (pdf_area * count)`, so that direct radiance at x is the sum over samples of
/// `rho_x/pi * radiance * cos_l cos_x / d^2 * V`; or a punctual light (see [`SampleKind`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterSample {
    pub position: Vec3,
    pub normal: Vec3,
    pub radiance: Vec3,
    pub kind: SampleKind,
    /// For a punctual light, the farthest the geometry can be from it (its distance to the
    /// sphere around the geometry, far side), so that its shadow maps reach that far; 0 for
    /// points on emitter triangles (which lie within the geometry).
    pub reach: f32,
    /// The emitter triangle a point sample lies on; None for a punctual light.
    pub tri: Option<u32>,
}

/// What an [`EmitterSample`] stands for, and so how its light reaches a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SampleKind {
    /// A point on an emitter triangle, as above.
    Area,
    /// Half a point light: its intensity `radiance` (W/sr, over the light's pick
    /// probability) into the hemisphere around `normal`; a point light is two samples, one
    /// around `normal` and one around `-normal`.
    PointHalf,
    /// A spot light: intensity `radiance` (W/sr) along the axis `normal`, with glTF's cone
    /// falloff between the two cosines.
    Spot { cos_inner: f32, cos_outer: f32 },
    /// A point light outside the geometry: its intensity `radiance` (W/sr) toward the
    /// geometry, which lies within the square frustum about `normal` whose half-width is
    /// `tan_half` (< 1) at unit distance: one shadow face, zoomed to that frustum.
    PointCone { tan_half: f32 },
    /// A directional light: irradiance `radiance` (W/m^2) travelling along `normal`.
    /// `position` is the centre of a square `2 extent` wide facing it behind the geometry
    /// (its shadow map's).
    Directional { extent: f32 },
    /// A direction drawn from the environment, drawn as a directional light: irradiance
    /// `radiance` (`L(w) / (pdf(w) count)`, W/m^2) travelling along `normal`. `position` is the
    /// centre of a square `2 extent` wide facing it behind the geometry, fitted to the
    /// geometry's box (not its sphere), and the map's depth range is `reach`.
    Environment { extent: f32 },
}

impl SampleKind {
    /// Whether the sample is one of a stratified draw whose count sets its variance (a point
    /// on an emitter triangle or a direction of the environment), rather than a punctual
    /// light taken exactly.
    pub fn is_sampled(&self) -> bool {
        matches!(self, SampleKind::Area | SampleKind::Environment { .. })
    }
}

impl EmitterSample {
    /// The irradiance this sample gives at `x` on a surface with unit normal `n`, without
    /// visibility (direct radiance is `rho/pi` times the sum of these over the samples that
    /// see `x`), with the point and normal whose visibility from `x` counts. None: no light.
    pub fn irradiance_at(&self, x: Vec3, n: Vec3) -> Option<(Vec3, Vec3, Vec3)> {
        if let SampleKind::Directional { .. } | SampleKind::Environment { .. } = self.kind {
            let cos_x = -n.dot(self.normal);
            let back = x - self.normal * self.normal.dot(x - self.position);
            return (cos_x > 0.0).then(|| (self.radiance * cos_x, back, Vec3::ZERO));
        }
        let d = x - self.position;
        let d2 = d.length_squared();
        if d2 <= 0.0 {
            return None;
        }
        let w = d / d2.sqrt();
        let cos_l = self.normal.dot(w);
        let cos_x = -n.dot(w);
        if cos_l <= 0.0 || cos_x <= 0.0 {
            return None;
        }
        let (f, nl) = match self.kind {
            SampleKind::Area => (cos_l, self.normal),
            SampleKind::PointHalf | SampleKind::PointCone { .. } => (1.0, Vec3::ZERO),
            SampleKind::Spot {
                cos_inner,
                cos_outer,
            } => (
                LightKind::Spot {
                    cos_inner,
                    cos_outer,
                }
                .falloff(cos_l),
                Vec3::ZERO,
            ),
            SampleKind::Directional { .. } | SampleKind::Environment { .. } => unreachable!(),
        };
        (f > 0.0).then(|| (self.radiance * (f * cos_x / d2), self.position, nl))
    }
}

/// The orthographic shadow map along unit direction `n` that holds the box of `corners`:
/// the centre of its square (behind the box along `n`, at the middle of the box's projection
/// across), its half-width (the larger of the projection's two, 1% wider) and its depth range.
/// Narrower than the sphere around the box, so its texels are finer (by up to `sqrt 3` for a
/// cube seen along an axis).
fn fit_map(n: Vec3, corners: &[Vec3]) -> (Vec3, f32, f32) {
    let (t, b) = crate::math::basis(n);
    let range = |a: Vec3| {
        corners
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), c| {
                (lo.min(a.dot(*c)), hi.max(a.dot(*c)))
            })
    };
    let ((t0, t1), (b0, b1), (n0, n1)) = (range(t), range(b), range(n));
    let half = (0.5 * (t1 - t0)).max(0.5 * (b1 - b0)).max(1e-6) * 1.01;
    let margin = 0.01 * half + 0.005 * (n1 - n0);
    let position = t * (0.5 * (t0 + t1)) + b * (0.5 * (b0 + b1)) + n * (n0 - margin);
    (position, half, (n1 - n0) + 2.0 * margin)
}

impl Frame {
    /// `count` emitter samples: the punctual lights first (each exactly, a point light as two
    /// samples, or one when it lies well outside the geometry, while they fit in `count` and leave one sample for the emitter triangles if
    /// there are any; else a stratified draw by power, weighted by its probability), then
    /// samples of the emitter triangles, stratified over the power CDF. The streams depend on
    /// the seed only (so a still scene's direct light does not change from frame to frame).
    pub fn emitter_samples(&self, seed: u64, count: usize) -> Vec<EmitterSample> {
        use rand::Rng;
        let em = &self.emitters;
        let mut out = self.punctual_samples(seed, count);
        let count = count - out.len();
        // The environment takes the rest, or half of it when emitter triangles share it.
        let env = match (&em.environment, em.tris.is_empty()) {
            (None, _) => 0,
            (Some(_), true) => count,
            (Some(_), false) => (count / 2).max(count.min(1)),
        };
        let count = count - env;
        let env_samples = self.environment_samples(seed, env);
        if em.tris.is_empty() || count == 0 {
            out.extend(env_samples);
            return out;
        }
        let mut r = crate::math::rng(&[seed, 0xd1ec7]);
        out.extend((0..count).map(|j| {
            let u = ((j as f32 + r.random::<f32>()) / count as f32).min(1.0 - 1e-7);
            let (e, p_e) = em.pick(u);
            let tri = em.tris[e] as usize;
            let b = crate::math::triangle_barycentrics(glam::Vec2::new(r.random(), r.random()));
            EmitterSample {
                position: self.point(tri, b.x, b.y),
                normal: self.normals[tri],
                radiance: self.emission_at(tri, b.x, b.y)
                    * (self.areas[tri] / (p_e * count as f32)),
                kind: SampleKind::Area,
                reach: 0.0,
                tri: Some(tri as u32),
            }
        }));
        out.extend(env_samples);
        out
    }

    /// `count` directions from the environment's distribution, each a directional light of
    /// irradiance `L / (pdf count)`: stratified in the first of the two numbers (bands of
    /// latitude in the map's distribution, so consecutive samples are strata), a golden-ratio
    /// sequence in the second (docs/math.md, "The environment").
    fn environment_samples(&self, seed: u64, count: usize) -> Vec<EmitterSample> {
        use rand::Rng;
        let em = &self.emitters;
        let Some(env) = em.environment.as_deref().filter(|_| count > 0) else {
            return Vec::new();
        };
        let mut r = crate::math::rng(&[seed, 0xe4f1]);
        let shift: f32 = r.random();
        let (lo, hi) = self.bounds();
        let corners: Vec<Vec3> = (0..8)
            .map(|k| {
                Vec3::new(
                    if k & 1 == 0 { lo.x } else { hi.x },
                    if k & 2 == 0 { lo.y } else { hi.y },
                    if k & 4 == 0 { lo.z } else { hi.z },
                )
            })
            .collect();
        (0..count)
            .filter_map(|j| {
                let u = glam::Vec2::new(
                    ((j as f32 + r.random::<f32>()) / count as f32).min(1.0 - 1e-7),
                    (shift + j as f32 * 0.618_034).fract(),
                );
                let (w, le, p) = env.sample(u);
                let (position, extent, reach) = fit_map(-w, &corners);
                (p > 0.0).then(|| EmitterSample {
                    position,
                    normal: -w,
                    radiance: le / (p * count as f32),
                    kind: SampleKind::Environment { extent },
                    reach,
                    tri: None,
                })
            })
            .collect()
    }

    /// The punctual lights' samples of [`Frame::emitter_samples`] (at most `count`).
    fn punctual_samples(&self, seed: u64, count: usize) -> Vec<EmitterSample> {
        use rand::Rng;
        let em = &self.emitters;
        if em.lights.is_empty() || count == 0 {
            return Vec::new();
        }
        let slots = |l: &PunctualLight| {
            if l.kind == LightKind::Point && self.cone_of(l).is_none() {
                2
            } else {
                1
            }
        };
        let needed: usize = em.lights.iter().map(slots).sum();
        let has_area = !em.tris.is_empty();
        // One slot at least for the emitter triangles and one for the environment, if any.
        let reserve = has_area as usize + em.environment.is_some() as usize;
        let mut out = Vec::new();
        if needed + reserve <= count {
            for l in &em.lights {
                self.push_light(&mut out, l, 1.0, None);
            }
            return out;
        }
        // Too many lights: `k` stratified picks by power; each fits in two slots.
        let share = 1.0 - em.area_share();
        // (With a single sample for both kinds the lights take it: `Pipeline::new` refuses
        // that count, so this only keeps any other caller from a panic.)
        let most = count.saturating_sub(reserve).max(1);
        let budget = ((count as f32 * share).round() as usize).clamp(1, most);
        let k = (budget / 2).max(1);
        let mut r = crate::math::rng(&[seed, 0x9c7a1]);
        for j in 0..k {
            let u = ((j as f32 + r.random::<f32>()) / k as f32).min(1.0 - 1e-7);
            let (i, p) = em.pick_light(u);
            // With one slot, a point light gives one random half, twice as bright.
            let half = (budget == 1).then(|| r.random::<bool>());
            self.push_light(&mut out, &em.lights[i], 1.0 / (p * k as f32), half);
        }
        out
    }

    /// For a point light outside the sphere around the geometry, far enough that the sphere
    /// fits a square frustum narrower than 90 degrees: the frustum's axis (toward the centre)
    /// and half-width at unit distance (1% wider than the sphere's cone).
    fn cone_of(&self, l: &PunctualLight) -> Option<(Vec3, f32)> {
        let (c, r) = self.emitters.sphere;
        let d = (c - l.position).length();
        let sin = r / d;
        (d.is_finite() && sin < 0.69).then(|| {
            let tan = sin / (1.0 - sin * sin).sqrt();
            ((c - l.position) / d, tan * 1.01)
        })
    }

    /// The sample(s) of one punctual light, scaled by `weight`; `half`: only one half of a
    /// point light (which, doubled).
    fn push_light(
        &self,
        out: &mut Vec<EmitterSample>,
        l: &PunctualLight,
        weight: f32,
        half: Option<bool>,
    ) {
        let radiance = l.intensity * weight;
        let (c, r) = self.emitters.sphere;
        let reach = (l.position - c).length() + r;
        match l.kind {
            LightKind::Point if half.is_none() && self.cone_of(l).is_some() => {
                let (axis, tan_half) = self.cone_of(l).unwrap();
                out.push(EmitterSample {
                    position: l.position,
                    normal: axis,
                    radiance,
                    kind: SampleKind::PointCone { tan_half },
                    reach,
                    tri: None,
                });
            }
            LightKind::Point => {
                let axis = if l.direction == Vec3::ZERO {
                    Vec3::Y
                } else {
                    l.direction
                };
                let sides: &[f32] = match half {
                    None => &[1.0, -1.0],
                    Some(true) => &[1.0],
                    Some(false) => &[-1.0],
                };
                let scale = if half.is_some() { 2.0 } else { 1.0 };
                for &s in sides {
                    out.push(EmitterSample {
                        position: l.position,
                        normal: axis * s,
                        radiance: radiance * scale,
                        kind: SampleKind::PointHalf,
                        reach,
                        tri: None,
                    });
                }
            }
            LightKind::Spot {
                cos_inner,
                cos_outer,
            } => out.push(EmitterSample {
                position: l.position,
                normal: l.direction,
                radiance,
                kind: SampleKind::Spot {
                    cos_inner,
                    cos_outer,
                },
                reach,
                tri: None,
            }),
            LightKind::Directional => {
                let extent = r * 1.01;
                out.push(EmitterSample {
                    position: c - l.direction * extent,
                    normal: l.direction,
                    radiance,
                    kind: SampleKind::Directional { extent },
                    reach: 2.0 * extent,
                    tri: None,
                });
            }
        }
    }
}
