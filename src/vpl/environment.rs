//! Light paths from the environment (pbrt-v4's infinite lights): a direction `w` toward the
//! environment drawn from its distribution (pdf `p(w)`), an origin uniform on the disk of
//! radius `R` (the sphere around the geometry) perpendicular to `w`, outside the sphere, and
//! the path travelling along `-w`. Its power over the density of that choice is
//! `L(w) / (p(w) / (pi R^2))`: every ray that can reach the geometry from that direction
//! crosses the disk, so E[power] is `pi R^2` times the radiance's integral
//! ([`crate::scene::Environment::power`]).

use crate::math::basis;
use crate::scene::Emitters;
use glam::{Vec2, Vec3};
use rand::Rng;
use std::f32::consts::PI;

/// Where a light path from the environment of `em` starts, its direction and its power over
/// the density of that choice (not yet divided by the probability of starting at the
/// environment). Zero power where the environment has none (no environment).
pub fn emit(em: &Emitters, r: &mut impl Rng) -> (Vec3, Vec3, Vec3) {
    let Some(env) = em.environment.as_deref() else {
        return (Vec3::ZERO, Vec3::Z, Vec3::ZERO);
    };
    let (w, le, p) = env.sample(Vec2::new(r.random(), r.random()));
    let (u1, u2): (f32, f32) = (r.random(), r.random());
    if p <= 0.0 {
        return (Vec3::ZERO, -w, Vec3::ZERO);
    }
    let (c, radius) = em.sphere;
    let (t, b) = basis(w);
    let rr = radius * u1.sqrt();
    let phi = 2.0 * PI * u2;
    let o = c + w * (radius * 1.01) + (t * phi.cos() + b * phi.sin()) * rr;
    (o, -w, le * (PI * radius * radius / p))
}
