//! The Sense frames, as the world writes them and as an agent reads its own: one iceoryx2
//! publish-subscribe service (`world/sense`), the world its one publisher, every agent a
//! subscriber. Once a tick the world packs every live robot's frame into one sample
//! ([`crate::sense_pack`]: an index by robot, then each record's fixed fields and its lists up
//! to their counts) and sends it; each agent receives the sample and copies its own record
//! out. The layout is the contract of `docs/protocol.md`.

use super::{senses_publisher, senses_service, SensesService, ServiceId};
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
    packer: SensePacker,
    /// The frame the world fills before it is packed.
    scratch: Box<Sense>,
    _service: SensesService,
}

impl SenseSink {
    /// Makes the run's Sense service for `sc.run.robots` robots.
    pub fn create(node: &Node<ipc::Service>, sc: &Scenario) -> TransportResult<Self> {
        let service = senses_service(node, sc, true)?;
        Ok(SenseSink {
            publisher: senses_publisher(&service, sc)?,
            packer: SensePacker::default(),
            scratch: Sense::zeroed(),
            _service: service,
        })
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
        let bytes = self.packer.bytes();
        let sample = self
            .publisher
            .loan_slice_uninit(bytes.len())
            .map_err(|source| TransportError::Loan {
                service: ServiceId::Senses,
                source,
            })?;
        let mut sample = sample.write_from_slice(bytes);
        *sample.user_header_mut() = SenseHeader {
            tick,
            robots: alive.len() as u32,
            bytes: bytes.len() as u32,
        };
        sample.send().map_err(|source| TransportError::Send {
            service: ServiceId::Senses,
            source,
        })?;
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
    _service: SensesService,
}

impl SenseSource {
    /// Opens the run's Sense service for robot `robot`'s agent.
    pub fn open(node: &Node<ipc::Service>, robot: u32) -> TransportResult<Self> {
        let service = senses_service_open(node)?;
        let subscriber = service
            .subscriber_builder()
            .buffer_size(1)
            .create()
            .map_err(|source| TransportError::Subscriber {
                service: ServiceId::Senses,
                source,
            })?;
        Ok(SenseSource {
            subscriber,
            robot,
            _service: service,
        })
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
                service: ServiceId::Senses,
                source,
            })?
        else {
            return Ok(None);
        };
        let tick = sample.user_header().tick;
        Ok(match unpack_into(sample.payload(), self.robot, into) {
            Ok(true) => Some(tick),
            _ => None,
        })
    }
}

fn senses_service_open(node: &Node<ipc::Service>) -> TransportResult<SensesService> {
    super::pub_sub(node, ServiceId::Senses, super::Reach::Open)
}
