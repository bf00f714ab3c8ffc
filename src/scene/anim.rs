//! Node animation channels: keyframes of translation, rotation or scale with STEP, LINEAR or
//! CUBICSPLINE interpolation, as glTF 2.0 defines them.

use glam::{Quat, Vec3, Vec4};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    Step,
    Linear,
    CubicSpline,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Property {
    Translation,
    Rotation,
    Scale,
}

/// A sampled value of a channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    Translation(Vec3),
    Rotation(Quat),
    Scale(Vec3),
}

/// One animated property of one node. `values` holds one Vec4 per key (xyz for translation and
/// scale, xyzw for rotation); for CUBICSPLINE three per key: in-tangent, value, out-tangent.
#[derive(Clone, Debug)]
pub struct Channel {
    pub node: usize,
    pub property: Property,
    pub interpolation: Interpolation,
    pub times: Vec<f32>,
    pub values: Vec<Vec4>,
}

impl Channel {
    fn key(&self, k: usize) -> Vec4 {
        match self.interpolation {
            Interpolation::CubicSpline => self.values[3 * k + 1],
            _ => self.values[k],
        }
    }

    /// The channel's value at time `t` (clamped to the keyed range).
    pub fn sample(&self, t: f32) -> Value {
        let v = self.sample_raw(t);
        match self.property {
            Property::Translation => Value::Translation(v.truncate()),
            Property::Scale => Value::Scale(v.truncate()),
            // A spline can pass through the zero quaternion: keep the nearest key's rotation.
            Property::Rotation => {
                let q = v
                    .try_normalize()
                    .unwrap_or_else(|| self.nearest_key(t).normalize());
                Value::Rotation(Quat::from_vec4(q))
            }
        }
    }

    fn nearest_key(&self, t: f32) -> Vec4 {
        let k = self.times.partition_point(|&x| x <= t);
        let k = match k {
            0 => 0,
            k if k >= self.times.len() => self.times.len() - 1,
            k if t - self.times[k - 1] < self.times[k] - t => k - 1,
            k => k,
        };
        self.key(k)
    }

    fn sample_raw(&self, t: f32) -> Vec4 {
        let n = self.times.len();
        if n == 1 || t <= self.times[0] {
            return self.key(0);
        }
        if t >= self.times[n - 1] {
            return self.key(n - 1);
        }
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let dt = t1 - t0;
        let s = if dt > 0.0 { (t - t0) / dt } else { 0.0 };
        let (a, b) = (self.key(k), self.key(k + 1));
        match self.interpolation {
            Interpolation::Step => a,
            Interpolation::Linear => match self.property {
                Property::Rotation => Quat::from_vec4(a).slerp(Quat::from_vec4(b), s).into(),
                _ => a.lerp(b, s),
            },
            Interpolation::CubicSpline => {
                let out_a = self.values[3 * k + 2];
                let in_b = self.values[3 * (k + 1)];
                let (s2, s3) = (s * s, s * s * s);
                a * (2.0 * s3 - 3.0 * s2 + 1.0)
                    + out_a * (dt * (s3 - 2.0 * s2 + s))
                    + b * (-2.0 * s3 + 3.0 * s2)
                    + in_b * (dt * (s3 - s2))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ch(property: Property, interpolation: Interpolation, times: &[f32], v: &[Vec4]) -> Channel {
        Channel {
            node: 0,
            property,
            interpolation,
            times: times.to_vec(),
            values: v.to_vec(),
        }
    }

    #[test]
    fn step_linear_and_clamping() {
        let v = [
            Vec4::new(0.0, 0.0, 0.0, 0.0),
            Vec4::new(2.0, 4.0, -2.0, 0.0),
        ];
        let step = ch(Property::Translation, Interpolation::Step, &[1.0, 3.0], &v);
        assert_eq!(step.sample(2.9), Value::Translation(Vec3::ZERO));
        assert_eq!(
            step.sample(3.0),
            Value::Translation(Vec3::new(2.0, 4.0, -2.0))
        );
        let lin = ch(
            Property::Translation,
            Interpolation::Linear,
            &[1.0, 3.0],
            &v,
        );
        assert_eq!(
            lin.sample(1.5),
            Value::Translation(Vec3::new(0.5, 1.0, -0.5))
        );
        assert_eq!(lin.sample(0.0), Value::Translation(Vec3::ZERO));
        assert_eq!(
            lin.sample(9.0),
            Value::Translation(Vec3::new(2.0, 4.0, -2.0))
        );
    }

    #[test]
    fn linear_rotation_is_slerp() {
        // 0 to 90 degrees about Y; at 1/3 of the way it must be 30 degrees (a lerp gives ~26.6).
        let q1 = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
        let lin = ch(
            Property::Rotation,
            Interpolation::Linear,
            &[0.0, 3.0],
            &[Quat::IDENTITY.into(), q1.into()],
        );
        let Value::Rotation(q) = lin.sample(1.0) else {
            panic!()
        };
        let (axis, angle) = q.to_axis_angle();
        assert!(
            (angle.to_degrees() - 30.0).abs() < 1e-3,
            "{}",
            angle.to_degrees()
        );
        assert!((axis - Vec3::Y).length() < 1e-4);
    }

    #[test]
    fn cubic_spline_hermite_by_hand() {
        // Keys at t=0 (value 0, out-tangent 2) and t=2 (value 1, in-tangent 0), 1D in x.
        // Hermite with dt=2 at s=0.5: h00=0.5, h10=0.125, h01=0.5, h11=-0.125
        // p = 0.5*0 + 0.125*2*2 + 0.5*1 + (-0.125)*2*0 = 1.0
        let v = [
            Vec4::ZERO,
            Vec4::ZERO,
            Vec4::new(2.0, 0.0, 0.0, 0.0),
            Vec4::ZERO,
            Vec4::new(1.0, 0.0, 0.0, 0.0),
            Vec4::ZERO,
        ];
        let c = ch(Property::Scale, Interpolation::CubicSpline, &[0.0, 2.0], &v);
        let Value::Scale(s) = c.sample(1.0) else {
            panic!()
        };
        assert!((s.x - 1.0).abs() < 1e-6, "{s}");
        // s = 0.25: h00=0.84375, h10=0.140625, h01=0.15625, h11=-0.046875 -> 0.5625+0.15625
        let Value::Scale(s) = c.sample(0.5) else {
            panic!()
        };
        assert!((s.x - (0.140625 * 4.0 + 0.15625)).abs() < 1e-6, "{s}");
        // Endpoints hit the key values.
        assert_eq!(c.sample(2.0), Value::Scale(Vec3::new(1.0, 0.0, 0.0)));
    }
}
