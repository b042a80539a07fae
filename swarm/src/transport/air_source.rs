//! The air, as the world writes it and as an agent reads it: one iceoryx2 publish-subscribe
//! service (`radio/air`), the world its one publisher, every agent a subscriber, with
//! `AllocationStrategy::Static` slots of the scenario's largest air
//! ([`super::air_max_len`]). The bytes are `swarm::air::write_air`'s layout.

use super::{air_publisher, air_service, AirSample, Generation, ServiceId};
use super::{TransportError, TransportResult};
use crate::frames::AirHeader;
use crate::scenario::Scenario;
use crate::wire::Received;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use serde::de::DeserializeOwned;
use std::sync::atomic::AtomicUsize;
use std::sync::Arc;

/// The world's side of the air.
pub struct AirSink {
    publisher: Publisher<ipc::Service, [u8], AirHeader>,
    /// The largest air a slot holds.
    max_len: usize,
    generation: Generation,
    _service: super::AirService,
}

impl AirSink {
    /// Makes the run's air for `sc.run.robots` agents.
    pub fn create(node: &Node<ipc::Service>, sc: &Scenario) -> TransportResult<Self> {
        Self::create_generation(node, sc, 0)
    }

    /// Makes the run's air of generation `generation` (the world's remake of a service whose
    /// segment shrank under it).
    pub fn create_generation(
        node: &Node<ipc::Service>,
        sc: &Scenario,
        generation: Generation,
    ) -> TransportResult<Self> {
        let service = air_service(node, sc, generation, true)?;
        Ok(AirSink {
            publisher: air_publisher(&service, sc)?,
            max_len: super::air_max_len(sc),
            generation,
            _service: service,
        })
    }

    /// How many agents' subscribers are connected.
    pub fn subscribers(&self) -> usize {
        self._service.dynamic_config().number_of_subscribers()
    }

    /// Publishes an air of `len` bytes; `fill` writes all of them and returns the header
    /// (which names the tick it is due at). An air longer than a slot cannot happen (the slot is the scenario's worst
    /// case); it is refused as [`TransportError::AirTooLong`], never written past the slot.
    pub fn publish(
        &mut self,
        len: usize,
        fill: impl FnOnce(&mut [u8]) -> AirHeader,
    ) -> TransportResult<()> {
        if len > self.max_len {
            return Err(TransportError::AirTooLong {
                len,
                max: self.max_len,
            });
        }
        let sample =
            self.publisher
                .loan_slice_uninit(len)
                .map_err(|source| TransportError::Loan {
                    service: ServiceId::Air {
                        generation: self.generation,
                    },
                    source,
                })?;
        // SAFETY: the slot is shared memory of the publisher's data segment, mapped from
        // tmpfs: its bytes are always initialised, and every u8 value is valid; `fill` writes
        // all `len` of them.
        let mut sample = unsafe { sample.assume_init() };
        let h = fill(sample.payload_mut());
        *sample.user_header_mut() = h;
        sample.send().map_err(|source| TransportError::Send {
            service: ServiceId::Air {
                generation: self.generation,
            },
            source,
        })?;
        Ok(())
    }
}

/// An agent's side of the air.
pub struct AirSource {
    subscriber: Subscriber<ipc::Service, [u8], AirHeader>,
    generation: Generation,
    /// The world's air data segment as this subscriber maps it, guarded: views into it
    /// outlive the agent's guarded reads.
    mapping: super::GuardedMapping,
    _service: super::AirService,
}

/// One air as an agent got it: the iceoryx2 sample, read in place.
pub struct AirGot(AirSample);

impl AirSource {
    /// Opens the run's air for an agent.
    pub fn open(node: &Node<ipc::Service>, sc: &Scenario) -> TransportResult<Self> {
        Self::open_generation(node, sc, 0)
    }

    /// Opens the run's air of generation `generation` for an agent.
    pub fn open_generation(
        node: &Node<ipc::Service>,
        sc: &Scenario,
        generation: Generation,
    ) -> TransportResult<Self> {
        let service = air_service(node, sc, generation, false)?;
        let subscriber = service
            .subscriber_builder()
            .buffer_size(1)
            .create()
            .map_err(|source| TransportError::Subscriber {
                service: ServiceId::Air { generation },
                source,
            })?;
        Ok(AirSource {
            subscriber,
            generation,
            mapping: Default::default(),
            _service: service,
        })
    }

    /// Waits until an air is there to receive (true), or `keep_trying` says to stop (false).
    pub fn wait_for(&self, keep_trying: &dyn Fn() -> bool) -> TransportResult<bool> {
        let service = ServiceId::Air {
            generation: self.generation,
        };
        super::wait_for_sample(&self.subscriber, service, keep_trying)
    }

    /// The newest air not received yet (buffer 1: none if already taken). The mapping it
    /// lies in is registered with the shrink guard ([`super::GuardedMapping`]).
    pub fn receive(&mut self) -> TransportResult<Option<AirGot>> {
        let got = self
            .subscriber
            .receive()
            .map_err(|source| TransportError::Receive {
                service: ServiceId::Air {
                    generation: self.generation,
                },
                source,
            })?;
        if let Some(sample) = &got {
            self.mapping.cover(sample.payload().as_ptr());
        }
        Ok(got.map(AirGot))
    }
}

impl AirGot {
    /// The tick the air is due at.
    pub fn tick(&self) -> u64 {
        self.0.user_header().tick
    }

    /// Robot `robot`'s inbox from it ([`super::air_inbox`]).
    pub fn inbox<M: DeserializeOwned>(
        self,
        robot: u32,
        zero_copy: bool,
        live: &Arc<AtomicUsize>,
        held_limit: usize,
        inbox: &mut Vec<Received<M>>,
    ) -> u32 {
        super::air_inbox(self.0, robot, zero_copy, live, held_limit, inbox)
    }
}
