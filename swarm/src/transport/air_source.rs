//! The air's two transports (`radio.air`), as the world writes it and as an agent reads it:
//! the world's ring of shared-memory slots (`swarm::air_ring`, the default) or one iceoryx2
//! publish-subscribe service. Both carry the same bytes (`swarm::air::write_air`), so what a
//! robot hears does not depend on the choice.

use super::{air_publisher, air_service, AirSample, ServiceId, TransportError, TransportResult};
use crate::air_ring::{AirRead, AirReader, AirWriter};
use crate::frames::AirHeader;
use crate::scenario::{AirTransport, Scenario};
use crate::wire::Received;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use serde::de::DeserializeOwned;
use std::sync::atomic::AtomicUsize;
use std::sync::Arc;

/// The world's side of the air.
pub enum AirSink {
    Ring(AirWriter),
    Iceoryx2 {
        publisher: Publisher<ipc::Service, [u8], AirHeader>,
        _service: super::AirService,
    },
}

impl AirSink {
    /// Makes the run's air (`radio.air`) for `sc.run.robots` agents.
    pub fn create(node: &Node<ipc::Service>, prefix: &str, sc: &Scenario) -> TransportResult<Self> {
        Ok(match sc.radio.air {
            AirTransport::Ring => AirSink::Ring(AirWriter::create(
                prefix,
                sc.run.robots,
                super::air_held(sc) as u32,
            )?),
            AirTransport::Iceoryx2 => {
                let service = air_service(node, sc, true)?;
                AirSink::Iceoryx2 {
                    publisher: air_publisher(&service, sc)?,
                    _service: service,
                }
            }
        })
    }

    /// Publishes an air of `len` bytes due at `tick`; `fill` writes all of them and returns
    /// the header.
    pub fn publish(
        &mut self,
        tick: u64,
        len: usize,
        fill: impl FnOnce(&mut [u8]) -> AirHeader,
    ) -> TransportResult<()> {
        match self {
            AirSink::Ring(w) => Ok(w.publish(tick, len, fill)?),
            AirSink::Iceoryx2 { publisher, .. } => {
                let sample =
                    publisher
                        .loan_slice_uninit(len)
                        .map_err(|source| TransportError::Loan {
                            service: ServiceId::Air,
                            source,
                        })?;
                // SAFETY: the slot is shared memory of the publisher's data segment, mapped
                // from tmpfs: its bytes are always initialised, and every u8 value is valid;
                // `fill` writes all `len` of them.
                let mut sample = unsafe { sample.assume_init() };
                let h = fill(sample.payload_mut());
                *sample.user_header_mut() = h;
                sample.send().map_err(|source| TransportError::Send {
                    service: ServiceId::Air,
                    source,
                })?;
                Ok(())
            }
        }
    }

    /// Robot `robot`'s agent is dead or replaced: what it held of the air is free again
    /// (the ring's hold cells; iceoryx2 reclaims a dead node's samples itself).
    pub fn release_robot(&self, robot: u32) {
        if let AirSink::Ring(w) = self {
            w.release_robot(robot);
        }
    }
}

/// An agent's side of the air.
pub enum AirSource {
    Ring(AirReader),
    Iceoryx2 {
        subscriber: Subscriber<ipc::Service, [u8], AirHeader>,
        _service: super::AirService,
    },
}

/// One air as an agent got it.
pub enum AirGot {
    Ring(AirRead),
    Iceoryx2(AirSample),
}

impl AirSource {
    /// Opens the run's air (`radio.air`) for robot `robot`'s agent.
    pub fn open(
        node: &Node<ipc::Service>,
        prefix: &str,
        sc: &Scenario,
        robot: u32,
    ) -> TransportResult<Self> {
        Ok(match sc.radio.air {
            AirTransport::Ring => AirSource::Ring(AirReader::open(prefix, robot)?),
            AirTransport::Iceoryx2 => {
                let service = air_service(node, sc, false)?;
                let subscriber = service
                    .subscriber_builder()
                    .buffer_size(1)
                    .create()
                    .map_err(|source| TransportError::Subscriber {
                        service: ServiceId::Air,
                        source,
                    })?;
                AirSource::Iceoryx2 {
                    subscriber,
                    _service: service,
                }
            }
        })
    }

    /// The newest air: the ring's published slot (the same one again until the world
    /// publishes the next), or iceoryx2's unread sample (buffer 1: none if already taken).
    pub fn receive(&mut self) -> TransportResult<Option<AirGot>> {
        match self {
            AirSource::Ring(r) => Ok(r.read()?.map(AirGot::Ring)),
            AirSource::Iceoryx2 { subscriber, .. } => Ok(subscriber
                .receive()
                .map_err(|source| TransportError::Receive {
                    service: ServiceId::Air,
                    source,
                })?
                .map(AirGot::Iceoryx2)),
        }
    }
}

impl AirGot {
    /// The tick the air is due at.
    pub fn tick(&self) -> u64 {
        match self {
            AirGot::Ring(a) => a.tick,
            AirGot::Iceoryx2(s) => s.user_header().tick,
        }
    }

    /// Robot `robot`'s inbox from it ([`super::air_inbox`], [`super::ring_inbox`]).
    pub fn inbox<M: DeserializeOwned>(
        self,
        robot: u32,
        zero_copy: bool,
        live: &Arc<AtomicUsize>,
        held_limit: usize,
        inbox: &mut Vec<Received<M>>,
    ) -> u32 {
        match self {
            AirGot::Ring(a) => super::ring_inbox(a, robot, zero_copy, live, held_limit, inbox),
            AirGot::Iceoryx2(s) => super::air_inbox(s, robot, zero_copy, live, held_limit, inbox),
        }
    }
}
