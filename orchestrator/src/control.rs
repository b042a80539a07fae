//! `orchestrator status` and `orchestrator kill`: live control of running runs from another
//! terminal, through the run registry.

use crate::registry::{self, RunEntry};
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

fn live_runs() -> Vec<RunEntry> {
    registry::list()
        .into_iter()
        .filter(|e| registry::pid_alive(e.orchestrator_pid))
        .collect()
}

pub fn status() -> i32 {
    let runs = live_runs();
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

pub fn kill(a: KillArgs) -> i32 {
    let runs = live_runs();
    let Some(e) = runs.iter().find(|e| e.run_id == a.run) else {
        let ids: Vec<&str> = runs.iter().map(|e| e.run_id.as_str()).collect();
        eprintln!(
            "error: --run {}: no such live run (live runs: {})",
            a.run,
            if ids.is_empty() {
                "none".into()
            } else {
                ids.join(", ")
            }
        );
        return 2;
    };
    let robots: Vec<u32> = a
        .robot
        .into_iter()
        .chain(a.robots.iter().copied())
        .collect();
    if robots.is_empty() {
        eprintln!("error: give --robot I or --robots I,J,...");
        return 2;
    }
    let n = e.agent_pids.len() as u32;
    if let Some(bad) = robots.iter().find(|&&r| r >= n) {
        eprintln!(
            "error: --robot {bad} is out of range: run {} has robots 0..={}",
            e.run_id,
            n.saturating_sub(1)
        );
        return 2;
    }
    for r in robots {
        let pid = e.agent_pids[r as usize];
        // Only a process of this run (its command line carries the run's prefix).
        let ours = std::fs::read(format!("/proc/{pid}/cmdline"))
            .map(|c| String::from_utf8_lossy(&c).contains(&e.prefix))
            .unwrap_or(false);
        if !ours {
            eprintln!("robot {r}: process {pid} is gone (already dead?)");
            continue;
        }
        // SAFETY: SIGKILL of an agent process of this run.
        unsafe {
            libc::kill(pid as i32, libc::SIGKILL);
        }
        println!("killed robot {r} (pid {pid}) of run {}", e.run_id);
    }
    0
}
