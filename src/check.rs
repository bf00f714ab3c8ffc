//! The checks every numeric setting goes through: NaN, infinity, sign and range, with a
//! message that names the setting as the caller passes it: in backquotes, the setting's name
//! (`` `exposure` NaN is not a number ``), which `irad`'s CLI reports as its flag.

use anyhow::{bail, Result};
use std::fmt::Display;

/// `value` must be a finite number in `lo..=hi` (`lo` excluded when `lo_open`).
pub fn float(flag: &str, value: f32, lo: f32, lo_open: bool, hi: f32) -> Result<()> {
    if value.is_nan() {
        bail!("{flag} NaN is not a number");
    }
    if value.is_infinite() {
        bail!("{flag} {value} is not a finite number");
    }
    let low_ok = if lo_open { value > lo } else { value >= lo };
    if !low_ok || value > hi {
        let low = if lo_open { ">" } else { ">=" };
        bail!("{flag} {value} is out of range: it must be {low} {lo} and at most {hi}");
    }
    Ok(())
}

/// `value` must be an integer in `lo..=hi`.
pub fn int<T: PartialOrd + Display + Copy>(flag: &str, value: T, lo: T, hi: T) -> Result<()> {
    if value < lo || value > hi {
        bail!("{flag} {value} is out of range: it must be {lo} to {hi}");
    }
    Ok(())
}
