use clap::Parser;

fn main() {
    irad::gpu::quiet_mesa_runtime_dir();
    if let Err(e) = irad::cli::run(irad::cli::Cli::parse()) {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
