//! Raw iceoryx2, the floor under the runtime's paths: `[u8]` publish-subscribe (loan, copy
//! the payload in, send; receive), the blocking wake-up through an iceoryx2 event. The first 8
//! payload bytes carry the sender's stamp.

use super::wait::{wait_for, NAP};
use super::{open_barrier, Mode, Parent, Peer};
use crate::bench::{now_ns, tick, BenchResult, ChildArgs};
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use swarm::transport::{
    self, EventCapacity, EventService, PubSubCapacity, PubSubService, Reach, ServiceId,
    TransportError,
};

/// Parent to child, child to parent: the data, and the wake-ups.
const DOWN: &str = "lat/down";
const UP: &str = "lat/up";
const DOWN_EV: &str = "lat/down-ev";
const UP_EV: &str = "lat/up-ev";

type Bytes = PubSubService<[u8], ()>;

/// One sender, one receiver, one sample in flight.
const DATA: PubSubCapacity = PubSubCapacity {
    publishers: 1,
    subscribers: 1,
    nodes: 2,
    buffer: 1,
    borrowed: None,
    history: Some(0),
    safe_overflow: None,
};
const WAKE: EventCapacity = EventCapacity {
    listeners: 1,
    notifiers: 1,
    nodes: 2,
};

/// One direction of the ping-pong: its data and event services.
struct Way {
    data: Bytes,
    wake: EventService,
}

impl Way {
    fn reach(node: &Node<ipc::Service>, data: &str, wake: &str, create: bool) -> BenchResult<Way> {
        Ok(Way {
            data: transport::pub_sub(
                node,
                ServiceId::from(data),
                Reach::create_if(create, || DATA),
            )?,
            wake: transport::event(
                node,
                ServiceId::from(wake),
                Reach::create_if(create, || WAKE),
            )?,
        })
    }

    fn publisher(&self, size: usize) -> BenchResult<Publisher<ipc::Service, [u8], ()>> {
        Ok(self
            .data
            .publisher_builder()
            .initial_max_slice_len(size)
            .allocation_strategy(AllocationStrategy::Static)
            .max_loaned_samples(1)
            .create()
            .map_err(|source| TransportError::Publisher {
                service: ServiceId::of(&self.data),
                source,
            })?)
    }

    fn subscriber(&self) -> BenchResult<Subscriber<ipc::Service, [u8], ()>> {
        Ok(self.data.subscriber_builder().create().map_err(|source| {
            TransportError::Subscriber {
                service: ServiceId::of(&self.data),
                source,
            }
        })?)
    }

    fn notifier(&self) -> BenchResult<Notifier<ipc::Service>> {
        Ok(self
            .wake
            .notifier_builder()
            .create()
            .map_err(|source| TransportError::Notifier {
                service: ServiceId::of(&self.wake),
                source,
            })?)
    }

    fn listener(&self) -> BenchResult<Listener<ipc::Service>> {
        Ok(self
            .wake
            .listener_builder()
            .create()
            .map_err(|source| TransportError::Listener {
                service: ServiceId::of(&self.wake),
                source,
            })?)
    }
}

/// The sending end of one direction.
struct Tx {
    publisher: Publisher<ipc::Service, [u8], ()>,
    notifier: Notifier<ipc::Service>,
    data: ServiceId,
    wake: ServiceId,
}

impl Tx {
    fn new(way: &Way, size: usize) -> BenchResult<Tx> {
        Ok(Tx {
            publisher: way.publisher(size)?,
            notifier: way.notifier()?,
            data: ServiceId::of(&way.data),
            wake: ServiceId::of(&way.wake),
        })
    }

    /// Sends `bytes`; when blocking, wakes the receiver.
    fn send(&self, bytes: &[u8], mode: Mode) -> BenchResult<()> {
        let s = self
            .publisher
            .loan_slice_uninit(bytes.len())
            .map_err(|source| TransportError::Loan {
                service: self.data.clone(),
                source,
            })?;
        s.write_from_slice(bytes)
            .send()
            .map_err(|source| TransportError::Send {
                service: self.data.clone(),
                source,
            })?;
        if mode == Mode::Block {
            self.notifier
                .notify()
                .map_err(|source| TransportError::Notify {
                    service: self.wake.clone(),
                    source,
                })?;
        }
        Ok(())
    }
}

/// The receiving end of one direction.
struct Rx {
    subscriber: Subscriber<ipc::Service, [u8], ()>,
    listener: Listener<ipc::Service>,
    data: ServiceId,
    wake: ServiceId,
}

impl Rx {
    fn new(way: &Way) -> BenchResult<Rx> {
        Ok(Rx {
            subscriber: way.subscriber()?,
            listener: way.listener()?,
            data: ServiceId::of(&way.data),
            wake: ServiceId::of(&way.wake),
        })
    }

    /// Waits for the next sample and returns its stamp.
    fn wait(&self, mode: Mode, peer: Peer) -> BenchResult<u64> {
        wait_for(
            mode,
            peer,
            || {
                let s = self
                    .subscriber
                    .receive()
                    .map_err(|source| TransportError::Receive {
                        service: self.data.clone(),
                        source,
                    })?;
                Ok(s.map(|s| u64::from_le_bytes(s.payload()[..8].try_into().expect("8"))))
            },
            || {
                self.listener
                    .timed_wait(|_| {}, NAP)
                    .map_err(|source| TransportError::Wait {
                        service: self.wake.clone(),
                        source,
                    })?;
                Ok(())
            },
        )
    }
}

/// The parent: sends `size` bytes, waits for the child's answer and records its one-hop time.
pub(super) fn parent(p: &Parent) -> BenchResult<Vec<u64>> {
    let config = transport::run_config(p.prefix)?;
    let node = transport::node(&config, "bench-lat-0")?;
    let down = Way::reach(&node, DOWN, DOWN_EV, true)?;
    let up = Way::reach(&node, UP, UP_EV, true)?;
    let tx = Tx::new(&down, p.size)?;
    let rx = Rx::new(&up)?;
    let child = p.spawn()?;
    let buf = vec![0x5au8; p.size];
    let mut ns = Vec::with_capacity(p.total as usize);
    let r = (|| -> BenchResult<()> {
        for _ in 0..p.total {
            tx.send(&buf, p.mode)?;
            let stamp = rx.wait(p.mode, Peer::Child)?;
            ns.push(now_ns().saturating_sub(stamp));
        }
        Ok(())
    })();
    tick::reap_children(vec![child]);
    r?;
    Ok(ns)
}

/// The child: answers each sample with `size` bytes stamped when it sends them.
pub(super) fn child(a: &ChildArgs, mode: Mode) -> BenchResult<()> {
    let barrier = open_barrier()?;
    let config = transport::run_config(&a.prefix)?;
    let node = transport::node(&config, "bench-lat-1")?;
    let down = Way::reach(&node, DOWN, DOWN_EV, false)?;
    let up = Way::reach(&node, UP, UP_EV, false)?;
    let rx = Rx::new(&down)?;
    let tx = Tx::new(&up, a.size)?;
    let mut buf = vec![0x5au8; a.size.max(8)];
    barrier.mark_ready(1);
    for _ in 0..a.rounds {
        rx.wait(mode, Peer::Parent)?;
        buf[..8].copy_from_slice(&now_ns().to_le_bytes());
        tx.send(&buf[..a.size], mode)?;
    }
    Ok(())
}
