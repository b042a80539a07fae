//! The `agent` binary: one robot's process running a built-in behaviour (started by
//! `orchestrator up`).

fn main() {
    swarm::agent::main_of::<swarm_bins::Builtin>()
}
