//! `orchestrator status` and `orchestrator kill`: live control of running runs from another
//! terminal, through the run registry.

use crate::exit;
use crate::registry::{self, RegistryError, RunEntry};
use clap::Args;

#[derive(Args, Debug)]
pub struct KillArgs {
    /// Run id (see `orchestrator status`).
    #[arg(long)]
    pub run: String,
    /// One robot to kill.
    #[arg(long, conflicts_with = "robots")]
    pub robot: Option<u32>,
    /// Several robots, comma separated.
    #[arg(long, value_delimiter = ',')]
    pub robots: Vec<u32>,
}

/// The registered runs whose orchestrator still runs (verified: its pid, binary and start
/// time).
fn live_runs() -> Result<Vec<RunEntry>, RegistryError> {
    Ok(registry::scan()?
        .0
        .into_iter()
        .filter(|e| e.orchestrator_is_live())
        .collect())
}

pub fn status() -> i32 {
    let runs = match live_runs() {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return exit::FAILED;
        }
    };
    if runs.is_empty() {
        println!("no runs");
        return 0;
    }
    println!(
        "{:<22} {:>9} {:>6} {:>5} {:>9}  {:>8} {:>8}  agents",
        "run", "tick", "alive", "dead", "restarted", "orch", "world"
    );
    for e in runs {
        let pids: Vec<String> = e.agent_pids.iter().map(|p| p.to_string()).collect();
        println!(
            "{:<22} {:>9} {:>6} {:>5} {:>9}  {:>8} {:>8}  {}",
            e.run_id,
            e.tick,
            e.alive,
            e.dead,
            e.restarted,
            e.orchestrator_pid,
            e.world_pid,
            pids.join(",")
        );
    }
    0
}

/// Why a kill order was refused.
#[derive(Debug, thiserror::Error)]
pub enum KillError {
    #[error("--run {run}: no such live run (live runs: {live})")]
    NoRun { run: String, live: String },
    #[error("give --robot I or --robots I,J,...")]
    NoRobot,
    #[error("--robot {robot} is out of range: run {run} has robots 0..={last}")]
    OutOfRange { robot: u32, run: String, last: u32 },
    #[error(transparent)]
    Registry(#[from] RegistryError),
}

/// SIGKILLs the agents of `robots` (each once, however often it is named) in live run `run`
/// (found in the run registry; only the recorded process, verified as this build's agent, or
/// an `[[agents]]` program with the run's prefix in its arguments, started at the recorded
/// time). One line per robot: killed, or gone.
/// `orchestrator kill` and the viewer's kill button both come here.
pub fn kill_robots(run: &str, robots: &[u32]) -> Result<Vec<String>, KillError> {
    let runs = live_runs()?;
    let Some(e) = runs.iter().find(|e| e.run_id == run) else {
        let ids: Vec<&str> = runs.iter().map(|e| e.run_id.as_str()).collect();
        return Err(KillError::NoRun {
            run: run.to_string(),
            live: if ids.is_empty() {
                "none".into()
            } else {
                ids.join(", ")
            },
        });
    };
    if robots.is_empty() {
        return Err(KillError::NoRobot);
    }
    let n = e.agent_pids.len() as u32;
    if let Some(&bad) = robots.iter().find(|&&r| r >= n) {
        return Err(KillError::OutOfRange {
            robot: bad,
            run: e.run_id.clone(),
            last: n.saturating_sub(1),
        });
    }
    let mut lines = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    for &r in robots.iter().filter(|&&r| seen.insert(r)) {
        let pid = e.agent_pids[r as usize];
        if pid == 0 {
            // Its agent runs on another host (`[[hosts]]`).
            lines.push(crate::hosts::kill::kill_remote(&e.prefix, &e.run_id, r));
            continue;
        }
        if !e.is_agent(pid, e.agent_starts[r as usize]) {
            lines.push(format!("robot {r}: process {pid} is gone (already dead?)"));
            continue;
        }
        // SAFETY: SIGKILL of an agent process of this run.
        unsafe {
            libc::kill(pid as i32, libc::SIGKILL);
        }
        lines.push(format!("killed robot {r} (pid {pid}) of run {}", e.run_id));
    }
    Ok(lines)
}

pub fn kill(a: KillArgs) -> i32 {
    let robots: Vec<u32> = a
        .robot
        .into_iter()
        .chain(a.robots.iter().copied())
        .collect();
    match kill_robots(&a.run, &robots) {
        Ok(lines) => {
            for l in lines {
                if l.starts_with("killed") {
                    println!("{l}");
                } else {
                    eprintln!("{l}");
                }
            }
            0
        }
        Err(e @ KillError::Registry(_)) => {
            eprintln!("error: {e}");
            exit::FAILED
        }
        Err(e) => {
            eprintln!("error: {e}");
            exit::BAD_INPUT
        }
    }
}
