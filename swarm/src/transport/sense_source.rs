//! The Sense frames, as the world writes them and as an agent reads its own: one iceoryx2
//! publish-subscribe service (`world/sense`), the world its one publisher, every agent a
//! subscriber. Once a tick the world packs every live robot's frame into one sample
//! ([`crate::sense_pack`]: an index by robot, then each record's fixed fields and its lists up
//! to their counts) and sends it; each agent receives the sample and copies its own record
//! out. The layout is the contract of `docs/protocol.md`.

use super::{senses_publisher, senses_service, Generation, SensesService, ServiceId};
use super::{TransportError, TransportResult};
use crate::frames::{Sense, SenseHeader, SENSE_FIXED_BYTES};
use crate::scenario::Scenario;
use crate::sense_pack::{unpack_into, SensePacker};
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;

/// The world's side of the Sense frames.
pub struct SenseSink {
    publisher: Publisher<ipc::Service, [u8], SenseHeader>,
    generation: Generation,
    packer: SensePacker,
    /// The frame the world fills before it is packed.
    scratch: Box<Sense>,
    _service: SensesService,
}

impl SenseSink {
    /// Makes the run's Sense service for `sc.run.robots` robots.
    pub fn create(node: &Node<ipc::Service>, sc: &Scenario) -> TransportResult<Self> {
        Self::create_generation(node, sc, 0)
    }

    /// Makes the run's Sense service of generation `generation` (the world's remake of a
    /// service whose segment shrank under it).
    pub fn create_generation(
        node: &Node<ipc::Service>,
        sc: &Scenario,
        generation: Generation,
    ) -> TransportResult<Self> {
        let service = senses_service(node, sc, generation, true)?;
        Ok(SenseSink {
            publisher: senses_publisher(&service, sc)?,
            generation,
            packer: SensePacker::default(),
            scratch: Sense::zeroed(),
            _service: service,
        })
    }

    /// Takes over `old`'s last packed frames (for [`SenseSink::republish`]): the world's remake
    /// of the service sends the tick's frames again from the new one.
    pub fn take_packed(&mut self, old: &mut SenseSink) {
        std::mem::swap(&mut self.packer, &mut old.packer);
    }

    /// How many agents' subscribers are connected.
    pub fn subscribers(&self) -> usize {
        self._service.dynamic_config().number_of_subscribers()
    }

    /// Publishes tick `tick`'s frame of every robot `alive` says is live, each written by
    /// `sense(i, frame)` into a frame whose fixed fields are zero (its lists are written up
    /// to their counts; what lies beyond is whatever an earlier tick left).
    pub fn publish(
        &mut self,
        tick: u64,
        alive: &[bool],
        mut sense: impl FnMut(u32, &mut Sense),
    ) -> TransportResult<()> {
        self.packer.begin(alive.len() as u32);
        for (i, _) in alive.iter().enumerate().filter(|(_, a)| **a) {
            zero_fixed(&mut self.scratch);
            sense(i as u32, &mut self.scratch);
            self.packer.push(i as u32, &self.scratch);
        }
        self.send_packed(tick, alive.len() as u32)
    }

    /// Sends the frames the last [`SenseSink::publish`] packed, again, as tick `tick`'s of
    /// `robots` robots: the world's second send of a tick into a service it made anew (the
    /// frames are the same bytes; sensing is not run twice, its noise draws stay as they were).
    pub fn republish(&mut self, tick: u64, robots: u32) -> TransportResult<()> {
        self.send_packed(tick, robots)
    }

    fn send_packed(&mut self, tick: u64, robots: u32) -> TransportResult<()> {
        let bytes = self.packer.bytes();
        let service = ServiceId::Senses {
            generation: self.generation,
        };
        let sample = self
            .publisher
            .loan_slice_uninit(bytes.len())
            .map_err(|source| TransportError::Loan {
                service: service.clone(),
                source,
            })?;
        let mut sample = sample.write_from_slice(bytes);
        *sample.user_header_mut() = SenseHeader {
            tick,
            robots,
            bytes: bytes.len() as u32,
        };
        sample
            .send()
            .map_err(|source| TransportError::Send { service, source })?;
        Ok(())
    }
}

fn zero_fixed(s: &mut Sense) {
    // SAFETY: Sense is plain old data, valid when zeroed; its first SENSE_FIXED_BYTES are
    // its fixed fields.
    unsafe { std::ptr::write_bytes(s as *mut Sense as *mut u8, 0, SENSE_FIXED_BYTES) };
}

/// An agent's side of its Sense frames.
pub struct SenseSource {
    subscriber: Subscriber<ipc::Service, [u8], SenseHeader>,
    robot: u32,
    generation: Generation,
    /// The world's Sense data segment as this subscriber maps it, guarded (as the air's).
    mapping: super::GuardedMapping,
    _service: SensesService,
}

impl SenseSource {
    /// Opens the run's Sense service for robot `robot`'s agent.
    pub fn open(node: &Node<ipc::Service>, robot: u32) -> TransportResult<Self> {
        Self::open_generation(node, robot, 0)
    }

    /// Opens the run's Sense service of generation `generation` for robot `robot`'s agent.
    pub fn open_generation(
        node: &Node<ipc::Service>,
        robot: u32,
        generation: Generation,
    ) -> TransportResult<Self> {
        let service = super::pub_sub(node, ServiceId::Senses { generation }, super::Reach::Open)?;
        let subscriber = service
            .subscriber_builder()
            .buffer_size(1)
            .create()
            .map_err(|source| TransportError::Subscriber {
                service: ServiceId::Senses { generation },
                source,
            })?;
        Ok(SenseSource {
            subscriber,
            robot,
            generation,
            mapping: Default::default(),
            _service: service,
        })
    }

    /// Waits until a frame is there to receive (true), or `keep_trying` says to stop (false).
    pub fn wait_for(&self, keep_trying: &dyn Fn() -> bool) -> TransportResult<bool> {
        let service = ServiceId::Senses {
            generation: self.generation,
        };
        super::wait_for_sample(&self.subscriber, service, keep_trying)
    }

    /// The newest frame not handed out yet, copied into `into` (the fixed fields and the
    /// lists up to their counts); its tick. None: no sample since the last call, or none for
    /// this robot in it (dead, or a record that does not parse: the world wrote it, so that
    /// cannot happen while the world is sound).
    pub fn receive(&mut self, into: &mut Sense) -> TransportResult<Option<u64>> {
        let Some(sample) = self
            .subscriber
            .receive()
            .map_err(|source| TransportError::Receive {
                service: ServiceId::Senses {
                    generation: self.generation,
                },
                source,
            })?
        else {
            return Ok(None);
        };
        self.mapping.cover(sample.payload().as_ptr());
        let tick = sample.user_header().tick;
        Ok(match unpack_into(sample.payload(), self.robot, into) {
            Ok(true) => Some(tick),
            _ => None,
        })
    }
}
