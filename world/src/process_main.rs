//! `world --run-dir DIR --prefix P`: the world process of a run (started by the orchestrator);
//! the `world` binary (bins/) calls [`main`].

use clap::Parser;
use std::path::PathBuf;
use swarm::scenario::Scenario;

#[derive(Parser)]
#[command(about = "The world process of a swarm run (started by `orchestrator up`)")]
struct Args {
    #[arg(long)]
    run_id: String,
    #[arg(long)]
    prefix: String,
    /// The run folder; holds the resolved scenario.toml and receives the outputs.
    #[arg(long)]
    run_dir: PathBuf,
    /// Flush recording.bin after every tick, for a live viewer (`orchestrator up --view`).
    #[arg(long)]
    live: bool,
}

/// The world process of a binary composed with plug-in `P` (bins/src/bin/world.rs): registers
/// `P`'s sections and missions, parses its flags, loads the run's scenario.toml, runs, exits.
pub fn main<P: swarm::plugin::Plugin + crate::mission::Missions>() {
    swarm::plugin::register_plugin::<P>();
    crate::mission::register::<P>();
    // SAFETY: prctl with constant arguments.
    unsafe {
        libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
    }
    swarm::transport::quiet_logs();
    // As the orchestrator does (for a world started by hand): one robot costs ~8 descriptors.
    swarm::limits::raise_nofile();
    let args = Args::parse();
    let sc = match Scenario::load(&args.run_dir.join("scenario.toml")) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("world: {e}");
            std::process::exit(2);
        }
    };
    let a = crate::process::WorldArgs {
        run_id: args.run_id,
        prefix: args.prefix,
        run_dir: args.run_dir,
        scenario: sc,
        live: args.live,
    };
    match crate::process::run(&a) {
        Ok(code) => std::process::exit(code),
        Err(e) => {
            eprintln!("world: {e}");
            std::process::exit(1);
        }
    }
}
