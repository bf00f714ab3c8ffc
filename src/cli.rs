//! `irad`'s command line: clap over the library's settings ([`crate::config`]). Every flag is
//! a field of a config type, whose `Default` supplies the help's defaults; this module only
//! names the subcommands and hands each its settings.

use crate::config;
use anyhow::Result;
use clap::{Parser, Subcommand};
use std::path::PathBuf;

/// irad: instant radiosity with temporally coherent virtual point lights.
#[derive(Parser, Debug)]
#[command(version, about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render frames on the GPU by instant radiosity (frames, preview.gif, run.json)
    Render(config::Render),
    /// Path-trace the ground truth (CPU, next-event estimation with MIS)
    Reference(config::Reference),
    /// Samplers x VPL counts on one animation against a cached reference: metrics, charts, report.html
    Compare(config::Compare),
    /// Run job INDEX of the plan in DIR (written by `irad compare/reference --plan DIR`),
    /// unless it has finished; a job cut short is redone (docs/cluster.md)
    Job {
        /// The plan's folder
        dir: PathBuf,
        /// The job's index in DIR/plan.json (a Slurm array's $SLURM_ARRAY_TASK_ID)
        index: usize,
    },
    /// Time whole frames per stage (CPU stages and GPU passes) for several VPL counts and sizes
    Bench(config::Bench),
    /// Error and flicker of an image sequence (folder of frame_FFFF.exr/.png) against a reference
    Metrics(config::Metrics),
    /// Open a window that renders the scene continuously: orbit, pan and fly the camera,
    /// play and scrub the time, switch scene, method, sampler and knobs; --split A,B shows two
    /// samplers side by side with their live flicker (docs/view.md)
    #[cfg(feature = "view")]
    View(crate::view::View),
    /// Print the graphics adapters found and the one irad chooses
    Info {
        #[arg(long, value_enum, default_value_t = config::Render::default().backend)]
        backend: crate::gpu::BackendChoice,
    },
    /// List the built-in scenes and what each stresses, or inspect one scene
    Scenes {
        /// A built-in scene name or a .gltf/.glb path: print its triangles, emitters and their
        /// power, cameras, animation, bounds and the loader's warnings
        scene: Option<String>,
        /// Write the built-in scenes' glTF files into this folder (how scenes/ is made)
        #[arg(long)]
        generate: Option<PathBuf>,
        /// Let a glTF scene read buffer and image files outside its own folder (absolute
        /// URIs, `..`, symbolic links leading out); refused by default
        #[arg(long)]
        allow_outside_paths: bool,
    },
}

impl Command {
    /// Checks the command's settings (what `run` does first).
    pub fn validate(&self) -> Result<()> {
        match self {
            Command::Render(c) => c.validate(),
            Command::Reference(c) => c.validate(),
            Command::Compare(c) => c.validate(),
            Command::Bench(c) => c.validate(),
            Command::Metrics(c) => c.validate(),
            #[cfg(feature = "view")]
            Command::View(c) => c.validate(),
            Command::Info { .. } | Command::Scenes { .. } | Command::Job { .. } => Ok(()),
        }
    }
}

/// Flags a subcommand takes through a settings type it shares with others but does not use:
/// given, they are refused rather than silently ignored.
const UNUSED: &[(&str, &[&str], &str)] = &[
    (
        "bench",
        &["vpls", "size", "frames", "overwrite", "components"],
        "each --configs VPLS@WxH sets the VPL count and image size, and bench renders frames 0.. of its own into --out without cleaning it",
    ),
    (
        "view",
        &["frames", "overwrite", "components"],
        "the view plays the whole animation from time 0 (the slider scrubs it) and saves frames under new names in --out",
    ),
];

/// Parses the command line (exiting with clap's message on an error), refusing the flags of
/// [`UNUSED`].
pub fn parse() -> Cli {
    use clap::{CommandFactory, FromArgMatches};
    let matches = Cli::command().get_matches();
    for (sub, flags, why) in UNUSED {
        let Some(m) = matches.subcommand_matches(sub) else {
            continue;
        };
        for f in flags.iter() {
            if m.value_source(f) == Some(clap::parser::ValueSource::CommandLine) {
                Cli::command()
                    .error(
                        clap::error::ErrorKind::ArgumentConflict,
                        format!("--{f} is not used by `irad {sub}`: {why}"),
                    )
                    .exit();
            }
        }
    }
    // --collect DIR takes the study from DIR/plan.json: another flag would be ignored.
    for sub in ["compare", "reference"] {
        let Some(m) = matches.subcommand_matches(sub) else {
            continue;
        };
        if m.value_source("collect") != Some(clap::parser::ValueSource::CommandLine) {
            continue;
        }
        let cmd = Cli::command();
        let args: Vec<String> = cmd
            .find_subcommand(sub)
            .map(|c| c.get_arguments().map(|a| a.get_id().to_string()).collect())
            .unwrap_or_default();
        for id in m.ids() {
            if id != "collect"
                && args.iter().any(|a| a == id.as_str())
                && m.value_source(id.as_str()) == Some(clap::parser::ValueSource::CommandLine)
            {
                Cli::command()
                    .error(
                        clap::error::ErrorKind::ArgumentConflict,
                        format!(
                            "--{} is not used with --collect: the study's settings are the plan's (DIR/plan.json)",
                            id.as_str().replace('_', "-")
                        ),
                    )
                    .exit();
            }
        }
    }
    Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit())
}

/// The flags of [`config::Cluster`] (each takes a value).
fn cluster_flags() -> Vec<String> {
    use clap::Args;
    config::Cluster::augment_args(clap::Command::new("cluster"))
        .get_arguments()
        .filter_map(|a| a.get_long().map(|l| format!("--{l}")))
        .collect()
}

/// The arguments of a subcommand without the cluster's flags: `irad COMMAND ARGS` is the
/// study on one machine.
pub fn study_args(args: &[String]) -> Vec<String> {
    let flags = cluster_flags();
    let mut out = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        if a == "--" {
            out.push(a.clone());
            out.extend(it.by_ref().cloned());
            break;
        }
        if flags.iter().any(|f| f == a) {
            it.next();
            continue;
        }
        if flags.iter().any(|f| a.starts_with(&format!("{f}="))) {
            continue;
        }
        out.push(a.clone());
    }
    out
}

/// The study a plan was written from: its arguments parsed as `irad COMMAND ARGS`, in the
/// folder they were given in (made the current one: jobs and --collect run there).
pub fn study_of(
    plan: &crate::commands::cluster::PlanFile,
) -> Result<crate::commands::cluster::Study> {
    use crate::commands::cluster::Study;
    std::env::set_current_dir(&plan.cwd).map_err(|e| {
        anyhow::anyhow!(
            "{}: cannot enter the folder the plan was written in ({e}): the plan's paths are relative to it",
            plan.cwd.display()
        )
    })?;
    let argv = ["irad".to_string(), plan.command.clone()]
        .into_iter()
        .chain(plan.args.iter().cloned());
    let cli = Cli::try_parse_from(argv).map_err(|e| {
        anyhow::anyhow!(
            "the plan's arguments `{}` do not parse: {}",
            plan.args.join(" "),
            e.render()
        )
    })?;
    cli.command.validate()?;
    // The chunks are the plan's.
    match cli.command {
        Command::Compare(mut c) => {
            c.cluster.chunk_frames = plan.chunk_frames;
            Ok(Study::Compare(Box::new(c)))
        }
        Command::Reference(mut r) => {
            r.cluster.chunk_frames = plan.chunk_frames;
            Ok(Study::Reference(Box::new(r)))
        }
        _ => anyhow::bail!(
            "a plan's command is compare or reference, not {}",
            plan.command
        ),
    }
}

/// The command line's arguments after the subcommand's name.
fn subcommand_args() -> Vec<String> {
    std::env::args().skip(2).collect()
}

/// Reads the plan in `dir` and its study (entering the plan's folder of origin); returns the
/// plan's folder made absolute first.
fn open_plan(
    dir: &std::path::Path,
) -> Result<(
    PathBuf,
    crate::commands::cluster::PlanFile,
    crate::commands::cluster::Study,
)> {
    let dir = std::path::absolute(dir)?;
    let plan = crate::commands::cluster::read_plan(&dir)?;
    let study = study_of(&plan)?;
    Ok((dir, plan, study))
}

/// An error as the command line reports it: each setting the library names (`` `ism_size` ``)
/// written as the flag that sets it (`--ism-size`), from the flags of every subcommand.
pub fn report(e: &anyhow::Error) -> String {
    use clap::CommandFactory;
    let cmd = Cli::command();
    let mut flags = std::collections::HashSet::new();
    for sub in std::iter::once(&cmd).chain(cmd.get_subcommands()) {
        for a in sub.get_arguments() {
            if let Some(l) = a.get_long() {
                flags.insert(l.replace('-', "_"));
            }
        }
    }
    let text = format!("{e:#}");
    let mut out = String::with_capacity(text.len());
    let mut rest = text.as_str();
    while let Some(a) = rest.find('`') {
        let Some(b) = rest[a + 1..].find('`') else {
            break;
        };
        let name = &rest[a + 1..a + 1 + b];
        out.push_str(&rest[..a]);
        if flags.contains(name) {
            out.push_str("--");
            out.push_str(&name.replace('_', "-"));
        } else {
            out.push_str(&rest[a..a + b + 2]);
        }
        rest = &rest[a + b + 2..];
    }
    out.push_str(rest);
    out
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    use crate::commands;
    cli.command.validate()?;
    match cli.command {
        Command::Render(c) => {
            crate::interrupt::install()?;
            commands::render::render(&c).map(|_| ())
        }
        Command::Reference(c) => {
            if let Some(dir) = &c.cluster.plan {
                let args = study_args(&subcommand_args());
                return commands::cluster::plan_reference(&c, dir, args).map(|_| ());
            }
            if let Some(dir) = &c.cluster.collect {
                let (dir, plan, study) = open_plan(dir)?;
                let commands::cluster::Study::Reference(r) = study else {
                    anyhow::bail!(
                        "{}: a plan of `irad {}`: collect it with `irad {} --collect`",
                        dir.display(),
                        plan.command,
                        plan.command
                    );
                };
                return commands::cluster::collect_reference(&r, &dir, &plan);
            }
            crate::interrupt::install()?;
            commands::reference::reference(&c).map(|_| ())
        }
        Command::Compare(c) => {
            if let Some(dir) = &c.cluster.plan {
                let args = study_args(&subcommand_args());
                return commands::cluster::plan_compare(&c, dir, args).map(|_| ());
            }
            if let Some(dir) = &c.cluster.collect {
                let (dir, plan, study) = open_plan(dir)?;
                let commands::cluster::Study::Compare(c) = study else {
                    anyhow::bail!(
                        "{}: a plan of `irad {}`: collect it with `irad {} --collect`",
                        dir.display(),
                        plan.command,
                        plan.command
                    );
                };
                return commands::cluster::collect_compare(&c, &dir, &plan);
            }
            commands::compare::compare(&c)
        }
        Command::Job { dir, index } => {
            let (dir, plan, study) = open_plan(&dir)?;
            commands::cluster::run_job(&dir, &plan, &study, index).map(|_| ())
        }
        Command::Bench(c) => commands::bench::bench(&c),
        #[cfg(feature = "view")]
        Command::View(v) => crate::view::view(&v),
        Command::Metrics(m) => {
            commands::metrics::metrics(&m.test, &m.reference, m.out.as_deref())?;
            match &m.scene {
                Some(s) => commands::metrics::warped(
                    &m.test,
                    &m.reference,
                    s,
                    m.fps,
                    m.camera.as_ref(),
                    m.out.as_deref(),
                    &crate::scene::load::LoadOptions {
                        allow_outside_paths: m.allow_outside_paths,
                    },
                ),
                None => Ok(()),
            }
        }
        Command::Info { backend } => commands::info(backend),
        Command::Scenes {
            scene,
            generate,
            allow_outside_paths,
        } => commands::scenes(
            scene.as_deref(),
            generate.as_deref(),
            &crate::scene::load::LoadOptions {
                allow_outside_paths,
            },
        ),
    }
}

/// The knobs' flags, one a knob of [`config::KNOBS`]: its name, help, default and value type.
impl clap::Args for config::SamplerKnobs {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        config::KNOBS.iter().fold(cmd, |cmd, k| {
            // clap keeps names as &'static str: the few built here live for the process.
            let leak = |s: String| -> &'static str { Box::leak(s.into_boxed_str()) };
            let help: Vec<&str> = k.help.lines().map(str::trim).collect();
            let mut a = clap::Arg::new(k.name)
                .long(k.name)
                .help(help.join(" "))
                .allow_hyphen_values(true)
                .value_name(leak(k.name.to_uppercase().replace('-', "_")));
            a = if k.integer() {
                a.value_parser(clap::value_parser!(u32))
            } else {
                a.value_parser(clap::value_parser!(f32))
            };
            if let Some(d) = k.default() {
                a = a.default_value(leak(if k.integer() {
                    (d as u32).to_string()
                } else {
                    (d as f32).to_string()
                }));
            }
            cmd.arg(a)
        })
    }
    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

impl clap::FromArgMatches for config::SamplerKnobs {
    fn from_arg_matches(m: &clap::ArgMatches) -> std::result::Result<Self, clap::Error> {
        let mut k = config::SamplerKnobs::default();
        k.update_from_arg_matches(m)?;
        Ok(k)
    }
    fn update_from_arg_matches(
        &mut self,
        m: &clap::ArgMatches,
    ) -> std::result::Result<(), clap::Error> {
        for k in config::KNOBS {
            let v = if k.integer() {
                m.get_one::<u32>(k.name).map(|&v| v as f64)
            } else {
                m.get_one::<f32>(k.name).map(|&v| v as f64)
            };
            if let Some(v) = v {
                k.set(self, v);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Result<Command, String> {
        let mut argv = vec!["irad"];
        argv.extend_from_slice(args);
        Cli::try_parse_from(argv)
            .map(|c| c.command)
            .map_err(|e| e.to_string())
    }

    /// The error for `args`, from clap's parse or from validate().
    fn error(args: &[&str]) -> String {
        match parse(args) {
            Err(e) => e,
            Ok(c) => match c.validate() {
                Err(e) => report(&e),
                Ok(()) => panic!("irad {} was accepted", args.join(" ")),
            },
        }
    }

    #[test]
    fn the_help_defaults_are_the_library_defaults() {
        let Command::Render(r) = parse(&["render"]).unwrap() else {
            panic!()
        };
        let d = config::Render::default();
        assert_eq!(r.vpls, d.vpls);
        assert_eq!(r.sequence.size, d.sequence.size);
        assert_eq!(r.quality.ism_size, d.quality.ism_size);
        assert_eq!(r.quality.aa, d.quality.aa);
        assert_eq!(r.sampler.mh_escape, d.sampler.mh_escape);
        assert_eq!(r.sampler.smc_rate, d.sampler.smc_rate);
        assert_eq!(r.sampler.smc_follow, d.sampler.smc_follow);
        assert_eq!(r.out, d.out);
        let Command::Compare(c) = parse(&["compare"]).unwrap() else {
            panic!()
        };
        assert_eq!(c.vpls, config::Compare::default().vpls);
        assert_eq!(c.samplers, config::Compare::default().samplers);
        let Command::Bench(b) = parse(&["bench"]).unwrap() else {
            panic!()
        };
        assert_eq!(b.cases, config::Bench::default().cases);
        assert_eq!(b.render.out, config::Bench::default().render.out);
    }

    /// Every numeric flag of every command, given NaN, infinity, a negative number and a value
    /// past its range, is refused with a message that names the flag.
    #[test]
    fn every_numeric_flag_is_checked_and_named() {
        let floats = [
            ("render", "--fps"),
            ("render", "--clamp"),
            ("render", "--eps"),
            ("render", "--mh-rate"),
            ("render", "--smc-rate"),
            ("render", "--smc-follow"),
            ("render", "--rmsmc-ess"),
            ("render", "--rmsmc-rate"),
            ("render", "--rmsmc-follow"),
            ("render", "--ism-bias"),
            ("render", "--exposure"),
            ("reference", "--fps"),
            ("reference", "--exposure"),
            ("compare", "--fps"),
            ("compare", "--clamp"),
            ("compare", "--eps"),
            ("compare", "--mh-rate"),
            ("compare", "--smc-rate"),
            ("compare", "--smc-follow"),
            ("compare", "--rmsmc-ess"),
            ("compare", "--ism-bias"),
            ("compare", "--exposure"),
            ("bench", "--fps"),
            ("bench", "--exposure"),
            ("bench", "--mh-rate"),
            ("bench", "--smc-rate"),
            ("bench", "--ism-bias"),
        ];
        for (cmd, flag) in floats {
            for bad in ["nan", "inf", "-inf", "-1", "1e30"] {
                let e = error(&[cmd, flag, bad]);
                assert!(e.contains(flag), "irad {cmd} {flag} {bad}: {e}");
                assert!(!e.contains("-- -1"), "clap's tip instead of a check: {e}");
            }
        }
        let ints = [
            ("render", "--vpls", "0", "70000"),
            ("render", "--candidates", "0", "99999999"),
            ("render", "--camera-points", "0", "99999999"),
            ("render", "--mh-escape", "", "100000"),
            ("render", "--ism-size", "48", "4096"),
            ("render", "--ism-points", "", "99999999"),
            ("render", "--interleave", "", "9"),
            ("render", "--pull-levels", "", "100"),
            ("render", "--light-samples", "", "100000"),
            ("render", "--shadow-size", "4", "100000"),
            ("render", "--aa", "", "9"),
            ("render", "--edge-rays", "", "33"),
            ("render", "--compensate", "", "257"),
            ("render", "--accumulate", "", "4097"),
            ("compare", "--aa", "", "9"),
            ("bench", "--aa", "", "9"),
            ("reference", "--spp", "0", "99999999"),
            ("compare", "--vpls", "0", "70000"),
            ("compare", "--spp", "0", "99999999"),
            ("compare", "--show-vpls", "7", "70000"),
            ("compare", "--camera-points", "0", "99999999"),
            ("compare", "--pull-levels", "", "100"),
            ("bench", "--repeat", "0", "99999"),
            ("bench", "--light-samples", "", "100000"),
        ];
        for (cmd, flag, low, high) in ints {
            for bad in [low, high, "-1", "nan", "1.5"] {
                if bad.is_empty() {
                    continue;
                }
                let e = error(&[cmd, flag, bad]);
                assert!(e.contains(flag), "irad {cmd} {flag} {bad}: {e}");
            }
        }
    }

    /// `--camera` on every command that renders or measures a scene: bad syntax (clap's parse),
    /// non-finite or far points, eye on target, field of view 0, 180 or past it (validate), each
    /// refused naming the flag and what is wrong.
    #[test]
    fn camera_is_checked_and_named_on_every_command() {
        let bad = [
            ("0,0,1:0,0,0", "EYE:TARGET:FOV"),
            ("0,0:0,0,0:40", "three numbers"),
            ("0,0,x:0,0,0:40", "'x' in the eye"),
            ("nan,0,1:0,0,0:40", "eye is not a finite"),
            ("0,0,1:0,inf,0:40", "target is not a finite"),
            ("1e30,0,1:0,0,0:40", "farther than"),
            ("1,2,3:1,2,3:40", "same point"),
            ("0,0,1:0,0,0:0", "field of view 0 degrees"),
            ("0,0,1:0,0,0:180", "between 0 and 180"),
            ("0,0,1:0,0,0:-40", "between 0 and 180"),
            ("0,0,1:0,0,0:nan", "field of view NaN"),
        ];
        for cmd in [
            &["render"][..],
            &["reference"],
            &["compare"],
            &["bench"],
            &["metrics", "a", "b", "--scene", "cornell"],
        ] {
            for (spec, why) in bad {
                let mut args = cmd.to_vec();
                args.extend(["--camera", spec]);
                let e = error(&args);
                assert!(
                    e.contains("--camera") && e.contains(why),
                    "irad {}: {e}",
                    args.join(" ")
                );
            }
            let mut args = cmd.to_vec();
            args.extend(["--camera", "0,1,3.4:0,1,0:39.3"]);
            parse(&args).unwrap().validate().unwrap();
        }
        let Command::Render(r) = parse(&["render", "--camera", "-1,2.5,3:0,1e-3,0:20"]).unwrap()
        else {
            panic!()
        };
        let c = r.sequence.camera.unwrap();
        assert_eq!(c.eye, glam::Vec3::new(-1.0, 2.5, 3.0));
        assert_eq!(c.target, glam::Vec3::new(0.0, 1e-3, 0.0));
        assert_eq!(c.fov_deg, 20.0);
        let e = error(&["metrics", "a", "b", "--camera", "0,0,1:0,0,0:40"]);
        assert!(e.contains("--camera needs --scene"), "{e}");
    }

    /// A plan's arguments are the study's without the cluster's flags, in either form.
    #[test]
    fn a_plans_arguments_leave_out_the_cluster_flags() {
        let args: Vec<String> = [
            "cornell",
            "--size",
            "8x8",
            "--plan",
            "d",
            "--gres=none",
            "--chunk-frames",
            "3",
            "--out",
            "o",
            "--max-running=2",
            "--cpus-per-job",
            "1",
            "--spp",
            "4",
        ]
        .map(String::from)
        .to_vec();
        assert_eq!(
            study_args(&args),
            ["cornell", "--size", "8x8", "--out", "o", "--spp", "4"]
        );
        let e = error(&["compare", "--plan", "d", "--collect", "d"]);
        assert!(e.contains("--collect"), "{e}");
        let e = error(&["compare", "--chunk-frames", "0"]);
        assert!(e.starts_with("--chunk-frames 0"), "{e}");
    }

    #[test]
    fn the_failures_the_review_found_are_refused_for_the_right_reason() {
        assert!(error(&["reference", "--exposure", "nan"]).contains("--exposure NaN"));
        assert!(error(&["render", "--ism-bias", "nan"]).contains("--ism-bias NaN"));
        let e = error(&["render", "--pull-levels", "100"]);
        assert!(
            e.contains("--pull-levels 100") && e.contains("0 to 6"),
            "{e}"
        );
        let e = error(&["render", "--vpls", "0"]);
        assert!(e.starts_with("--vpls 0"), "{e}");
        let e = error(&["render", "--frames", "4294967295"]);
        assert!(e.contains("past the last frame"), "{e}");
        let e = error(&["render", "--clamp", "-1"]);
        assert!(e.contains("--clamp -1 is out of range"), "{e}");
        // A bench configuration's VPL count is named as the --configs entry it is (issue 24).
        let e = error(&["bench", "--configs", "0@64x64"]);
        assert!(e.starts_with("--configs 0@64x64"), "{e}");
        let e = error(&["compare", "--samplers", "cdf", "--vpls", "4,0"]);
        assert!(e.starts_with("--vpls 0"), "{e}");
    }
}
