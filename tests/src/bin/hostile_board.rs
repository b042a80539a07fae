//! A hostile agent program for the e2e tests (tests/tests/tamper.rs): it attaches to its
//! robot's act blackboard (`runtime.acts = "blackboard"`) like an agent, then moves the write
//! counters of both tick slots' heads without end (iceoryx2's own zero-copy update, nothing
//! written): a read of either entry by the world retries while the counter moves.
//! Only the public iceoryx2 API and the documented protocol (docs/protocol.md 3.4) are used.

use iceoryx2::prelude::*;
use swarm::barrier::TickBarrier;
use swarm::transport::{self, ActHead};

fn arg(name: &str) -> String {
    let args: Vec<String> = std::env::args().collect();
    args.windows(2)
        .find(|w| w[0] == name)
        .map(|w| w[1].clone())
        .unwrap_or_else(|| panic!("{name} missing: {args:?}"))
}

fn main() {
    transport::quiet_logs();
    let robot: u32 = arg("--robot").parse().expect("--robot");
    let prefix = arg("--prefix");
    let config = transport::run_config(&prefix).expect("config");
    let node = transport::node(&config, &format!("agent-{robot}")).expect("node");
    let name = ServiceName::new(&format!("robot/{robot}/board")).expect("name");
    let board = node
        .service_builder(&name)
        .blackboard_opener::<u32>()
        .open()
        .expect("open the board");
    let writer = board.writer_builder().create().expect("writer");
    let barrier = TickBarrier::open_agent(&prefix).expect("barrier");
    let attach = barrier.mark_ready(robot);
    writer
        .entry::<u64>(&0)
        .expect("attach entry")
        .update_with_copy(attach);
    let mut heads = [1u32, 2].map(|k| Some(writer.entry::<ActHead>(&k).expect("head entry")));
    loop {
        for h in heads.iter_mut() {
            let v = h.take().expect("handle").loan_uninit();
            // SAFETY: the write cell is shared memory the world initialised when it made the
            // board (every byte of an ActHead value is valid); nothing is written to it.
            *h = Some(unsafe { v.assume_init_and_update() });
        }
    }
}
