//! Past one machine: the flags that write a study as a plan of independent jobs for a cluster
//! (`--plan DIR`), and that merge what the jobs wrote (`--collect DIR`). See docs/cluster.md.

use super::check;
use anyhow::{bail, Result};
use std::path::PathBuf;

/// How a study is split into jobs and submitted to Slurm.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Cluster {
    /// Write the study as a plan of independent jobs into DIR (plan.json; Slurm job arrays
    /// and submit.sh) and render nothing; `irad job DIR INDEX` runs one job
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "DIR", conflicts_with = "collect")
    )]
    pub plan: Option<PathBuf>,
    /// Merge the finished jobs of the plan in DIR into the outputs a run on one machine writes
    /// (the study's settings are the plan's: give no other flags)
    #[cfg_attr(feature = "cli", arg(long, value_name = "DIR"))]
    pub collect: Option<PathBuf>,
    /// Frames per reference job of a plan
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Cluster::default().chunk_frames, allow_hyphen_values = true))]
    pub chunk_frames: u32,
    /// The most tasks of one job array that Slurm runs at once (--array=A-B%K)
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Cluster::default().max_running, allow_hyphen_values = true))]
    pub max_running: u32,
    /// CPU cores each job of a plan asks Slurm for (--cpus-per-task)
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Cluster::default().cpus_per_job, allow_hyphen_values = true))]
    pub cpus_per_job: u32,
    /// The generic resource a GPU job of a plan asks Slurm for (--gres); `none` asks for none
    /// (a node whose renderer needs no GPU of Slurm's, e.g. Mesa's llvmpipe)
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Cluster::default().gres))]
    pub gres: String,
}

impl Default for Cluster {
    fn default() -> Self {
        Cluster {
            plan: None,
            collect: None,
            chunk_frames: 4,
            max_running: 32,
            cpus_per_job: 8,
            gres: "gpu:1".to_string(),
        }
    }
}

impl Cluster {
    pub fn validate(&self) -> Result<()> {
        if self.plan.is_some() && self.collect.is_some() {
            bail!("`plan` writes a plan and `collect` merges one: give one of them");
        }
        check::int("`chunk_frames`", self.chunk_frames, 1, 100_000)?;
        check::int("`max_running`", self.max_running, 1, 100_000)?;
        check::int("`cpus_per_job`", self.cpus_per_job, 1, 4096)?;
        let ok = |c: char| c.is_ascii_alphanumeric() || "_:.-".contains(c);
        if self.gres.is_empty() || !self.gres.chars().all(ok) {
            bail!(
                "`gres` '{}': it must be a Slurm generic resource such as gpu:1 (letters, digits and _ : . -), or none",
                self.gres
            );
        }
        Ok(())
    }

    /// The `--gres` a GPU job asks for, None for `none`.
    pub fn gpu_gres(&self) -> Option<&str> {
        (self.gres != "none").then_some(self.gres.as_str())
    }
}
