//! The samplers' knobs, each declared once in [`knobs!`]'s list below: its field, type,
//! default, flag, range, help text and the samplers that read it. From that one line come the
//! field of [`SamplerKnobs`] and its default, the check in [`SamplerKnobs::validate`], the
//! CLI's flag (`config` builds it from [`KNOBS`]) and what `irad compare --sweep` can vary.
//! Adding a knob is adding its line (and reading it in the sampler that uses it).

use super::SamplerKind;
use anyhow::Result;
use serde::Serialize;

/// What values a knob takes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Range {
    /// A finite number in `lo..=hi` (`lo` excluded when `lo_open`).
    Float { lo: f32, lo_open: bool, hi: f32 },
    /// A whole number in `lo..=hi`.
    Int { lo: u32, hi: u32 },
}

/// One knob: the flag's name (without dashes), its help, its range, the samplers that read
/// it, and how to read and set it on [`SamplerKnobs`] (as f64).
pub struct Knob {
    pub name: &'static str,
    pub help: &'static str,
    pub range: Range,
    pub used_by: &'static [SamplerKind],
    get: fn(&SamplerKnobs) -> Option<f64>,
    set: fn(&mut SamplerKnobs, f64),
}

impl std::fmt::Debug for Knob {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

impl PartialEq for Knob {
    fn eq(&self, o: &Knob) -> bool {
        self.name == o.name
    }
}

impl Serialize for Knob {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name)
    }
}

impl std::fmt::Display for Knob {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

impl Knob {
    /// The default (None: an optional knob, whose help says what it is left unset).
    pub fn default(&self) -> Option<f64> {
        self.get(&SamplerKnobs::default())
    }
    /// The knob's value in `k` (None: an optional knob left unset).
    pub fn get(&self, k: &SamplerKnobs) -> Option<f64> {
        (self.get)(k)
    }
    /// Sets the knob to `v` in `k` (a whole number for an integer knob).
    pub fn set(&self, k: &mut SamplerKnobs, v: f64) {
        (self.set)(k, v)
    }
    /// Whether the knob takes whole numbers.
    pub fn integer(&self) -> bool {
        matches!(self.range, Range::Int { .. })
    }
    /// Whether sampler `s` reads the knob.
    pub fn used_by(&self, s: SamplerKind) -> bool {
        self.used_by.contains(&s)
    }
    /// The knob as errors name a setting: `` `mh_rate` `` (the CLI writes `--mh-rate`).
    pub fn setting(&self) -> String {
        format!("`{}`", self.name.replace('-', "_"))
    }
    /// Checks `v` against the range, naming the setting.
    pub fn check(&self, v: f64) -> Result<()> {
        let flag = self.setting();
        match self.range {
            Range::Float { lo, lo_open, hi } => {
                crate::check::float(&flag, v as f32, lo, lo_open, hi)
            }
            Range::Int { lo, hi } => crate::check::int(&flag, v as u64, lo as u64, hi as u64),
        }
    }
    /// The knob named `name` (with or without its dashes).
    pub fn named(name: &str) -> Option<&'static Knob> {
        let name = name.trim().trim_start_matches("--");
        KNOBS.iter().find(|k| k.name == name)
    }
}

/// A knob's value as f64, for an optional knob or a plain one.
trait AsKnob: Copy {
    fn to_knob(self) -> Option<f64>;
    fn from_knob(v: f64) -> Self;
}
impl AsKnob for f32 {
    fn to_knob(self) -> Option<f64> {
        Some(self as f64)
    }
    fn from_knob(v: f64) -> Self {
        v as f32
    }
}
impl AsKnob for u32 {
    fn to_knob(self) -> Option<f64> {
        Some(self as f64)
    }
    fn from_knob(v: f64) -> Self {
        v as u32
    }
}
impl AsKnob for Option<f32> {
    fn to_knob(self) -> Option<f64> {
        self.map(|v| v as f64)
    }
    fn from_knob(v: f64) -> Self {
        Some(v as f32)
    }
}
impl AsKnob for Option<u32> {
    fn to_knob(self) -> Option<f64> {
        self.map(|v| v as f64)
    }
    fn from_knob(v: f64) -> Self {
        Some(v as u32)
    }
}

macro_rules! knobs {
    ($(
        $(#[doc = $doc:literal])+
        $field:ident : $ty:ty = $default:expr, $flag:literal, $range:expr, [$($kind:ident),*];
    )*) => {
        /// The samplers' knobs (see the module's list for each one's meaning and range).
        #[derive(Clone, Debug, PartialEq, Serialize)]
        pub struct SamplerKnobs {
            $($(#[doc = $doc])+ pub $field: $ty,)*
        }

        impl Default for SamplerKnobs {
            fn default() -> Self {
                SamplerKnobs { $($field: $default,)* }
            }
        }

        /// Every knob, in the order the help and the messages list them.
        pub static KNOBS: &[Knob] = &[$(Knob {
            name: $flag,
            help: concat!($($doc, "\n"),+),
            range: $range,
            used_by: &[$(SamplerKind::$kind),*],
            get: |k| AsKnob::to_knob(k.$field),
            set: |k, v| k.$field = AsKnob::from_knob(v),
        },)*];
    };
}

use Range::{Float, Int};

knobs! {
    /// MH: probability that a chain proposes in a frame where nothing moves (1: one step
    /// every frame; lower keeps VPLs longer). The rate rises with how far the target moved,
    /// see --mh-follow. 0.15 by default, so that the 8 frames --accumulate averages hold more
    /// than one set of VPLs (docs/math.md section 7, "The rate under accumulation")
    mh_rate: f32 = 0.15, "mh-rate", Float { lo: 0.0, lo_open: true, hi: 1.0 }, [Mh];
    /// MH: how fast the proposal rate follows the scene: rate = min(1, mh-rate + mh-follow *
    /// d), d the total-variation distance between the last frame's and this frame's target
    /// (0: a fixed rate)
    mh_follow: f32 = 10.0, "mh-follow", Float { lo: 0.0, lo_open: false, hi: 1000.0 }, [Mh];
    /// MH: extra proposals in a frame for a chain whose VPL no camera point sees (0: none)
    mh_escape: u32 = 8, "mh-escape", Int { lo: 0, hi: 1000 }, [Mh];
    /// SMC: probability that a slot takes a newborn particle in a frame (1: every frame, as
    /// cdf; lower keeps VPLs longer). The rate rises with how far the kept weights are off,
    /// see --smc-follow
    smc_rate: f32 = 0.05, "smc-rate", Float { lo: 0.0, lo_open: true, hi: 1.0 }, [Smc];
    /// SMC: how fast the renewal rate follows the kept weights: rate = min(1, smc-rate +
    /// smc-follow * D), D the spread of the kept particles' importance now over at birth (0:
    /// a fixed rate)
    smc_follow: f32 = 0.0, "smc-follow", Float { lo: 0.0, lo_open: false, hi: 1000.0 }, [Smc];
    /// RMSMC: resample the particles when their effective sample size falls below this
    /// fraction of the slots (0: never; 1: whenever their weights differ)
    rmsmc_ess: f32 = 0.5, "rmsmc-ess", Float { lo: 0.0, lo_open: false, hi: 1.0 }, [Rmsmc];
    /// RMSMC: probability that a slot makes a Metropolis-Hastings move in a frame where nothing
    /// moves (0: a still scene keeps every VPL, as frozen). The rate rises with how far the
    /// target moved, see --rmsmc-follow
    rmsmc_rate: f32 = 0.0, "rmsmc-rate", Float { lo: 0.0, lo_open: false, hi: 1.0 }, [Rmsmc];
    /// RMSMC: how fast the move rate follows the scene: rate = min(1, rmsmc-rate +
    /// rmsmc-follow * d), d the total-variation distance between the last frame's and this
    /// frame's importance over a fixed probe of paths (0: a fixed rate)
    rmsmc_follow: f32 = 2.0, "rmsmc-follow", Float { lo: 0.0, lo_open: false, hi: 1000.0 }, [Rmsmc];
    /// Defensive floor of the importance, as a fraction of its mean [default: 0.5 for mh,
    /// 0.05 for the others]
    eps: Option<f32> = None, "eps", Float { lo: 0.0, lo_open: false, hi: 1000.0 }, [Cdf, Mh, Rejection, Smc, Rmsmc];
    /// M: candidate VPLs a frame for cdf, mh and smc [default: 4 x --vpls]
    candidates: Option<u32> = None, "candidates", Int { lo: 1, hi: MAX_CANDIDATES }, [Cdf, Mh, Smc, Rmsmc];
    /// K: camera points for importance
    camera_points: u32 = 256, "camera-points", Int { lo: 1, hi: 1 << 20 }, [Cdf, Mh, Rejection, Smc, Rmsmc];
}

/// The defensive floor of cdf, smc and rejection: a VPL's weight is at most (1 + eps) / eps
/// = 21 times that of its draw without importance.
pub const EPS: f32 = 0.05;

/// mh's defensive floor: its weight bound (1 + eps) / eps = 3. A chain can sit for frames on
/// a VPL whose importance the camera points underestimate, and with the floor at 0.05 that
/// VPL's weight (up to 21 times a plain draw's) lights a blotch for as long: on `two-rooms`
/// (96x96, 256 VPLs, 8 frames accumulated) seeds 1, 2 and 4 measured relMSE 0.0192, 0.0924,
/// 0.0515 at 0.05 and 0.0136, 0.0180, 0.0317 at 0.5, with the same flicker (0.0090, 0.0092,
/// 0.0069 against 0.0090, 0.0097, 0.0070); 0.2 and 1 were between or worse.
pub const MH_EPS: f32 = 0.5;

/// The most candidate VPLs a frame (`candidates`): each costs a traced path and about 70
/// bytes, so 2^20 is about 70 MiB and seconds a frame on the CPU (2^24 ran out of time at
/// 1.1 GB).
pub const MAX_CANDIDATES: u32 = 1 << 20;

impl SamplerKnobs {
    /// Checks every knob against its range, naming its flag; `vpls` slots give the default M.
    pub fn validate(&self, vpls: u32) -> Result<()> {
        for k in KNOBS {
            if let Some(v) = k.get(self) {
                k.check(v)?;
            }
        }
        crate::check::int(
            "`candidates` (4 x `vpls`)",
            self.candidates(vpls),
            1,
            MAX_CANDIDATES,
        )
    }
    /// The defensive floor for sampler `kind`: `--eps`, or [`MH_EPS`] for mh and
    /// [`EPS`] for the others.
    pub fn eps(&self, kind: SamplerKind) -> f32 {
        self.eps
            .unwrap_or(if kind == SamplerKind::Mh { MH_EPS } else { EPS })
    }
    /// M for `vpls` slots: `--candidates`, or 4 a slot.
    pub fn candidates(&self, vpls: u32) -> u32 {
        self.candidates.unwrap_or(vpls.saturating_mul(4))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_knob_reads_and_sets_its_own_field() {
        for (i, k) in KNOBS.iter().enumerate() {
            let mut s = SamplerKnobs::default();
            assert_eq!(k.get(&s), k.default(), "{k}");
            // A value in range, different from the default, lands in this knob alone.
            let v = match k.range {
                Range::Float { hi, .. } => hi as f64,
                Range::Int { lo, .. } => lo as f64 + 3.0,
            };
            k.set(&mut s, v);
            assert_eq!(k.get(&s), Some(v), "{k}");
            for (j, other) in KNOBS.iter().enumerate() {
                if j != i {
                    assert_eq!(other.get(&s), other.default(), "{k} changed {other}");
                }
            }
            k.check(v).unwrap();
        }
        assert_eq!(Knob::named("--mh-rate").unwrap().name, "mh-rate");
        assert!(Knob::named("mh_rate").is_none());
        let e = Knob::named("mh-rate").unwrap().check(0.0).unwrap_err();
        assert!(e.to_string().contains("`mh_rate` 0 is out of range"), "{e}");
    }
}
