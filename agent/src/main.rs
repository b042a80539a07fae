//! `agent --robot I ...`: one robot's process. Started by the orchestrator.

use clap::Parser;
use std::path::PathBuf;
use swarm::scenario::Scenario;

#[derive(Parser)]
#[command(about = "One robot of a swarm run (started by `orchestrator up`)")]
struct Args {
    /// The robot this process runs.
    #[arg(long)]
    robot: u32,
    /// The run's iceoryx2 prefix.
    #[arg(long)]
    prefix: String,
    /// The resolved scenario of the run.
    #[arg(long)]
    scenario: PathBuf,
    /// The run id (for `ps` and logs).
    #[arg(long, default_value = "")]
    run_id: String,
}

fn main() {
    // Die with the orchestrator (it owns cleanup of the run).
    // SAFETY: prctl with constant arguments.
    unsafe {
        libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
    }
    swarm::transport::quiet_logs();
    let args = Args::parse();
    let sc = match Scenario::load(&args.scenario) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("agent {}: {e}", args.robot);
            std::process::exit(2);
        }
    };
    if args.robot >= sc.run.robots {
        eprintln!(
            "agent: --robot {} is out of range: allowed 0..={}",
            args.robot,
            sc.run.robots - 1
        );
        std::process::exit(2);
    }
    let a = agent::process::AgentArgs {
        robot: args.robot,
        prefix: args.prefix,
        scenario: sc,
    };
    match agent::process::run(&a) {
        Ok(code) => std::process::exit(code),
        Err(e) => {
            // A restarted agent can start just as the run ends: its services are gone with
            // the run, which is no fault of the agent's. Say nothing then.
            let run_over = swarm::barrier::TickBarrier::open_agent(&a.prefix)
                .map(|b| b.is_shutdown())
                .unwrap_or(true);
            if run_over {
                std::process::exit(agent::process::EXIT_WORLD_GONE);
            }
            eprintln!("agent {}: {e}", a.robot);
            std::process::exit(agent::process::EXIT_SETUP);
        }
    }
}
