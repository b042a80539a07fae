//! The `agent` binary: one robot's process running a built-in behaviour (started by
//! `orchestrator up`).

fn main() {
    agent::process_main::main()
}
