//! The `world` binary: one run's world process (started by `orchestrator up`).

fn main() {
    world::process_main::main::<swarm_bins::Builtin>()
}
