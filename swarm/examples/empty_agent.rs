//! An agent program whose behaviour does nothing (stands still, sends nothing): the Rust
//! baseline of the Python package's benchmark (`python/bench/tick.py`), the runtime's own
//! cost per robot-tick with no behaviour work. Built with
//! `cargo build --release -p swarm --example empty_agent`.

use swarm::{Behaviour, Command, Outbox, Received, Sense};

struct Empty;

impl Behaviour for Empty {
    type Msg = Vec<u8>;
    fn step_refs(
        &mut self,
        _: &Sense,
        _: &[&Received<Vec<u8>>],
        _: &mut Outbox<Vec<u8>>,
    ) -> Command {
        Command::default()
    }
}

fn main() {
    swarm::agent::main(|_| Ok::<_, std::convert::Infallible>(Empty))
}
