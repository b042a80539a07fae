//! The act path's iceoryx2 shapes, side by side in one process (issue 36): N robots each send
//! one act sample a round, the world receives and releases all N. `per-robot` = one service
//! a robot (1 publisher, 1 subscriber: today's `robot/<i>/act`); `one-service` = one service
//! with N publishers and the world's one subscriber (its `receive()` scans every connection).
//! `blackboard` = one blackboard service a robot (world creates and reads, the robot writes).
//! Prints the mean time a round of the world's side (receive + release of N samples) and of
//! the robots' side (N loans + sends). Run it under `valgrind --tool=callgrind` for
//! instruction counts, which a loaded machine does not move.
//!
//! `cargo run --release -p swarm --example act_shapes -- N ROUNDS` (SHAPE=per-robot, one-service
//! or blackboard for one of them).

use iceoryx2::prelude::*;
use std::time::{Duration, Instant};

/// The act sample's payload bytes (roam: 4 messages of 256 bytes, each with a 40-byte header).
const SLICE: usize = 4 * (40 + 256);

type Pub = iceoryx2::port::publisher::Publisher<ipc::Service, [u8], u64>;
type Sub = iceoryx2::port::subscriber::Subscriber<ipc::Service, [u8], u64>;
type Svc = iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, [u8], u64>;

fn service(node: &Node<ipc::Service>, name: &str, publishers: usize) -> Svc {
    node.service_builder(&ServiceName::new(name).unwrap())
        .publish_subscribe::<[u8]>()
        .user_header::<u64>()
        .max_publishers(publishers)
        .max_subscribers(1)
        .max_nodes(2)
        .subscriber_max_buffer_size(2)
        .history_size(0)
        .create()
        .unwrap()
}

fn publisher(s: &Svc) -> Pub {
    s.publisher_builder()
        .initial_max_slice_len(SLICE)
        .allocation_strategy(AllocationStrategy::Static)
        .max_loaned_samples(1)
        .create()
        .unwrap()
}

fn subscriber(s: &Svc) -> Sub {
    s.subscriber_builder().buffer_size(2).create().unwrap()
}

/// Runs `rounds` rounds: every publisher sends one sample, then the world takes them all
/// through `take` (which returns how many it received). Returns the mean (send, take) times.
fn rounds(pubs: &[Pub], rounds: u64, mut take: impl FnMut() -> usize) -> (Duration, Duration) {
    let (mut send, mut recv) = (Duration::ZERO, Duration::ZERO);
    for r in 0..rounds {
        let t = Instant::now();
        for p in pubs {
            let s = p.loan_slice_uninit(SLICE).unwrap();
            // SAFETY: static slots of shared memory, every byte value is valid.
            let mut s = unsafe { s.assume_init() };
            *s.user_header_mut() = r;
            s.send().unwrap();
        }
        let t2 = Instant::now();
        let got = take();
        assert_eq!(got, pubs.len(), "round {r}");
        send += t2 - t;
        recv += t2.elapsed();
    }
    (send / rounds as u32, recv / rounds as u32)
}

/// The act as a blackboard value: the round in its first 8 bytes, then the payload.
#[derive(Clone, Copy, Debug, ZeroCopySend)]
#[repr(C)]
struct BoardAct {
    round: u64,
    bytes: [u8; SLICE],
}

/// `blackboard` = one blackboard service a robot (the world creates it and reads key 0, the
/// robot's writer updates it: iceoryx2's triple-buffered `UnrestrictedAtomic`, no loan, no
/// return queue).
fn blackboard(node: &Node<ipc::Service>, n: u64, r: u64) {
    let t = Instant::now();
    let init = BoardAct {
        round: u64::MAX,
        bytes: [0; SLICE],
    };
    let svcs: Vec<_> = (0..n)
        .map(|i| {
            node.service_builder(&ServiceName::new(&format!("robot/{i}/board")).unwrap())
                .blackboard_creator::<u8>()
                .max_readers(1)
                .max_nodes(2)
                .add::<BoardAct>(0, init)
                .create()
                .unwrap()
        })
        .collect();
    let readers: Vec<_> = svcs
        .iter()
        .map(|s| s.reader_builder().create().unwrap())
        .collect();
    let rents: Vec<_> = readers
        .iter()
        .map(|rd| rd.entry::<BoardAct>(&0).unwrap())
        .collect();
    let writers: Vec<_> = svcs
        .iter()
        .map(|s| s.writer_builder().create().unwrap())
        .collect();
    let wents: Vec<_> = writers
        .iter()
        .map(|w| w.entry::<BoardAct>(&0).unwrap())
        .collect();
    let setup = t.elapsed();
    let (mut send, mut recv) = (Duration::ZERO, Duration::ZERO);
    let mut v = init;
    for round in 0..r {
        let t = Instant::now();
        for w in &wents {
            v.round = round;
            w.update_with_copy(v);
        }
        let t2 = Instant::now();
        let got = rents.iter().filter(|e| e.get().round == round).count();
        assert_eq!(got, n as usize, "round {round}");
        send += t2 - t;
        recv += t2.elapsed();
    }
    let (s, t) = (send / r as u32, recv / r as u32);
    println!("blackboard  N={n}: set-up {setup:?}, robots' sends {s:?} a round, world's receives {t:?} a round ({:?} a sample)", t / n as u32);
}

fn main() {
    let args: Vec<u64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("N ROUNDS"))
        .collect();
    let (n, r) = (
        args.first().copied().unwrap_or(50),
        args.get(1).copied().unwrap_or(1000),
    );
    set_log_level_from_env_or(LogLevel::Error);
    let prefix = format!("swactshape{}_", std::process::id());
    let mut config = Config::default();
    config.global.prefix = FileName::new(prefix.as_bytes()).unwrap();
    config
        .global
        .set_root_path(&Path::new(b"/dev/shm/swactshape_iox2/").unwrap());
    let node = NodeBuilder::new()
        .config(&config)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .unwrap();
    let which = std::env::var("SHAPE").unwrap_or_default();
    if which.is_empty() || which == "per-robot" {
        let t = Instant::now();
        let svcs: Vec<Svc> = (0..n)
            .map(|i| service(&node, &format!("robot/{i}/act"), 1))
            .collect();
        let subs: Vec<Sub> = svcs.iter().map(subscriber).collect();
        let pubs: Vec<Pub> = svcs.iter().map(publisher).collect();
        let setup = t.elapsed();
        let (s, t) = rounds(&pubs, r, || {
            subs.iter()
                .filter(|s| matches!(s.receive(), Ok(Some(_))))
                .count()
        });
        println!("per-robot   N={n}: set-up {setup:?}, robots' sends {s:?} a round, world's receives {t:?} a round ({:?} a sample)", t / n as u32);
    }
    if which.is_empty() || which == "one-service" {
        let t = Instant::now();
        let svc = service(&node, "robots/act", n as usize);
        let sub = subscriber(&svc);
        let pubs: Vec<Pub> = (0..n).map(|_| publisher(&svc)).collect();
        let setup = t.elapsed();
        let (s, t) = rounds(&pubs, r, || {
            let mut got = 0;
            while let Ok(Some(_)) = sub.receive() {
                got += 1;
            }
            got
        });
        println!("one-service N={n}: set-up {setup:?}, robots' sends {s:?} a round, world's receives {t:?} a round ({:?} a sample)", t / n as u32);
    }
    if which.is_empty() || which == "blackboard" {
        blackboard(&node, n, r);
    }
    drop(node);
    // Everything of this program in /dev/shm starts with `swactshape`: leave none of it.
    let _ = std::fs::remove_dir_all("/dev/shm/swactshape_iox2");
    for e in std::fs::read_dir("/dev/shm")
        .into_iter()
        .flatten()
        .flatten()
    {
        if e.file_name().to_string_lossy().starts_with(&prefix) {
            let _ = std::fs::remove_file(e.path());
        }
    }
}
