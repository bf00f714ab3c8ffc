fn main() {
    irad::gpu::quiet_mesa_runtime_dir();
    if let Err(e) = irad::cli::run(irad::cli::parse()) {
        // The reader of stdout has gone (`irad scenes | head -1`): nothing to say, no failure.
        if irad::commands::is_closed_pipe(&e) {
            std::process::exit(0);
        }
        if let Some(i) = e.downcast_ref::<irad::interrupt::Interrupted>() {
            eprintln!("{i}");
            std::process::exit(irad::interrupt::EXIT_STATUS);
        }
        eprintln!("error: {}", irad::cli::report(&e));
        std::process::exit(1);
    }
}
