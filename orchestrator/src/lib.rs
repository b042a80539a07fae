//! `orchestrator`: starts, watches, hurts and measures swarm runs.

mod agent_programs;
mod agent_spawn;
mod bench;
mod clean;
mod completions;
mod control;
mod exit;
mod experiment;
mod experiment_cbca;
mod experiment_formation;
mod experiment_hunt;
mod export;
mod hosts;
mod inprocess;
mod logs;
mod outcome;
mod outdir;
mod phase;
mod plugins;
mod prepare;
mod processes;
mod progress;
mod registry;
mod runid;
mod signals;
mod summary;
mod up;
mod view;

use clap::{FromArgMatches, Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "orchestrator",
    about = "Zero-copy multi-process swarm runtime",
    version
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

// Parsed once per process: the size of the largest variant (`up`'s flags) costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand)]
enum Cmd {
    /// Run a scenario: one world process and one agent process per robot.
    #[command(allow_negative_numbers = true)]
    Up(up::UpArgs),
    /// Run a grid of scenarios (modes x swarm sizes x seeds) and print the paper-style table.
    Experiment(experiment::ExperimentArgs),
    /// Measure the runtime against raw iceoryx2 and the futex floor.
    Bench(bench::BenchArgs),
    /// Remove everything dead runs left in /dev/shm and in the run registry.
    Clean,
    /// List the running runs: id, tick, robots alive / dead / restarted, pids.
    Status,
    /// SIGKILL agent processes of a running run.
    Kill(control::KillArgs),
    /// Replay a run in the browser: serves a page on 127.0.0.1 that plays its recording.bin.
    View(view::ViewArgs),
    /// Write a run's recording as CSV (one row per robot and tick), its events as CSV, or
    /// MCAP (for Foxglove).
    Export(export::ExportArgs),
    /// Print the agents' output (stdout and stderr, one log per robot in the run folder).
    Logs(logs::LogsArgs),
    /// Print a shell's completion script, e.g. `orchestrator completions bash`.
    Completions(completions::CompletionsArgs),
    /// Run this host's robots of a run across hosts: join the world's host at ENDPOINT and
    /// serve the robots the scenario's `[[hosts]]` places on NAME.
    Host(hosts::proxy::HostArgs),
    /// (internal) A benchmark child process.
    #[command(hide = true, name = "__bench-child")]
    BenchChild(bench::ChildArgs),
}

/// The `orchestrator` command line of a binary composed with plug-in `P` (bins/src/bin/
/// orchestrator.rs): registers `P`'s sections, missions and behaviours, then runs the command.
pub fn main<P: swarm::plugin::Plugin + world::mission::Missions>() {
    plugins::register::<P>();
    swarm::transport::quiet_logs();
    // Every robot costs the world descriptors; its children inherit the raised limit.
    swarm::limits::raise_nofile();
    let cli = match Cli::from_arg_matches(&completions::command().get_matches()) {
        Ok(c) => c,
        Err(e) => e.exit(),
    };
    if !matches!(cli.cmd, Cmd::Bench(_) | Cmd::BenchChild(_)) {
        // `orchestrator up | head`: a closed stdout ends us quietly, as for any Unix tool,
        // instead of a panic. These commands print only after their runs are cleaned up; the
        // benchmarks print as they go, so they keep the default (a write error, then cleanup).
        // SAFETY: setting a signal disposition before any thread or child exists.
        unsafe { libc::signal(libc::SIGPIPE, libc::SIG_DFL) };
    }
    let code = match cli.cmd {
        Cmd::Up(a) => up::up(a),
        Cmd::Host(a) => hosts::proxy::host(a),
        Cmd::Bench(a) => bench::bench(a),
        Cmd::BenchChild(a) => bench::child(a),
        Cmd::Status => control::status(),
        Cmd::Experiment(a) => experiment::experiment(a),
        Cmd::Kill(a) => control::kill(a),
        Cmd::View(a) => view::view(a),
        Cmd::Export(a) => export::export(a),
        Cmd::Completions(a) => completions::print(a),
        Cmd::Logs(a) => logs::logs(a),
        Cmd::Clean => match clean::clean_dead_runs() {
            Ok(r) => {
                for line in &r.ignored {
                    eprintln!("{line}");
                }
                println!(
                    "cleaned {} dead run(s): {} /dev/shm file(s), {} leftover process(es)",
                    r.runs, r.shm_files, r.processes
                );
                0
            }
            Err(e) => {
                eprintln!("error: {e}");
                exit::FAILED
            }
        },
    };
    std::process::exit(code);
}
