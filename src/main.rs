use clap::{Parser, Subcommand};
use irad::cli::SceneOpts;
use std::path::PathBuf;

/// irad: instant radiosity with temporally coherent virtual point lights.
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Path-trace the ground truth (CPU, next-event estimation with MIS)
    Reference {
        #[command(flatten)]
        opts: SceneOpts,
        /// Samples per pixel
        #[arg(long, default_value_t = 256)]
        spp: u32,
        /// Output folder
        #[arg(long, default_value = "out/reference")]
        out: PathBuf,
        /// Exposure of the PNG previews (the EXR files are linear, unscaled)
        #[arg(long, default_value_t = 1.0)]
        exposure: f32,
    },
    /// Render frames on the GPU by instant radiosity (frames, preview.gif, run.json)
    Render(irad::commands::RenderOpts),
    /// Time whole frames per stage (CPU stages and GPU passes) for several VPL counts and sizes
    Bench {
        #[command(flatten)]
        opts: irad::commands::RenderOpts,
        /// Configurations VPLS@WxH
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "256@256x256,1024@512x512"
        )]
        configs: Vec<irad::commands::BenchConfig>,
        /// Frames measured per configuration (after one warm-up frame)
        #[arg(long, default_value_t = 5)]
        repeat: u32,
    },
    /// Error and flicker of an image sequence (folder of frame_FFFF.exr/.png) against a reference
    Metrics {
        /// Folder of test frames
        test: PathBuf,
        /// Folder of reference frames
        reference: PathBuf,
        /// Where metrics.json and metrics.csv go [default: the test folder]
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Samplers x VPL counts on one animation against a cached reference: metrics, charts, report.html
    Compare(irad::report::compare::CompareOpts),
    /// Print the graphics adapters found and the one irad chooses
    Info {
        #[arg(long, value_enum, default_value = "auto")]
        backend: irad::gpu::BackendChoice,
    },
    /// List the built-in scenes and what each stresses, or inspect one scene
    Scenes {
        /// A built-in scene name or a .gltf/.glb path: print its triangles, emitters and their
        /// power, cameras, animation, bounds and the loader's warnings
        scene: Option<String>,
        /// Write the built-in scenes' glTF files into this folder (how scenes/ is made)
        #[arg(long)]
        generate: Option<PathBuf>,
    },
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Reference {
            opts,
            spp,
            out,
            exposure,
        } => irad::commands::reference(&opts, spp, &out, exposure).map(|_| ()),
        Command::Render(opts) => irad::commands::render(&opts),
        Command::Bench {
            opts,
            configs,
            repeat,
        } => irad::commands::bench(&opts, &configs, repeat.max(1)),
        Command::Metrics {
            test,
            reference,
            out,
        } => irad::commands::metrics(&test, &reference, out.as_deref()).map(|_| ()),
        Command::Compare(opts) => irad::report::compare::compare(&opts),
        Command::Info { backend } => irad::commands::info(backend),
        Command::Scenes { scene, generate } => {
            irad::commands::scenes(scene.as_deref(), generate.as_deref())
        }
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
