//! The Sense frames' two transports (`runtime.sense`), as the world writes them and as an
//! agent reads its own: the world's ring beside the air (`swarm::air_ring::sense`, the
//! default: one publication a tick for every robot) or one iceoryx2 service per robot. Both
//! hand the agent the same frame (the fixed fields and the lists up to their counts), so
//! what a robot senses does not depend on the choice.

use super::{sense_service, SenseService, ServiceId, TransportError, TransportResult};
use crate::air_ring::sense::{unpack_into, SensePacker, SENSE_RING};
use crate::air_ring::{AirReader, AirWriter};
use crate::frames::{AirHeader, Sense, SENSE_FIXED_BYTES};
use crate::scenario::{FrameTransport, Scenario};
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;

/// Hold cells of a robot in the Sense ring: one, for the read (the agent copies its record
/// out at once; nothing keeps a view of it).
const SENSE_HELD: u32 = 0;

/// One robot's Sense service as the world publishes it.
pub struct SensePort {
    publisher: Publisher<ipc::Service, Sense, ()>,
    _service: SenseService,
}

/// The world's side of the Sense frames.
pub enum SenseSink {
    Ring {
        writer: AirWriter,
        packer: SensePacker,
        /// The frame the world fills before it is packed.
        scratch: Box<Sense>,
    },
    Iceoryx2(Vec<SensePort>),
}

impl SenseSink {
    /// Makes the run's Sense transport (`runtime.sense`) for `sc.run.robots` robots.
    pub fn create(node: &Node<ipc::Service>, prefix: &str, sc: &Scenario) -> TransportResult<Self> {
        let n = sc.run.robots;
        Ok(match sc.runtime.sense {
            FrameTransport::Ring => SenseSink::Ring {
                writer: AirWriter::create_named(prefix, SENSE_RING, n, SENSE_HELD)?,
                packer: SensePacker::default(),
                scratch: Sense::zeroed(),
            },
            FrameTransport::Iceoryx2 => SenseSink::Iceoryx2(
                (0..n)
                    .map(|i| {
                        let service = sense_service(node, i, true)?;
                        let publisher = service
                            .publisher_builder()
                            .max_loaned_samples(1)
                            .create()
                            .map_err(|source| TransportError::Publisher {
                                service: ServiceId::Sense(i),
                                source,
                            })?;
                        Ok(SensePort {
                            publisher,
                            _service: service,
                        })
                    })
                    .collect::<TransportResult<Vec<_>>>()?,
            ),
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
        match self {
            SenseSink::Ring {
                writer,
                packer,
                scratch,
            } => {
                packer.begin(alive.len() as u32);
                for (i, _) in alive.iter().enumerate().filter(|(_, a)| **a) {
                    zero_fixed(scratch);
                    sense(i as u32, scratch);
                    packer.push(i as u32, scratch);
                }
                let bytes = packer.bytes();
                writer.publish(tick, bytes.len(), |out| {
                    out.copy_from_slice(bytes);
                    AirHeader {
                        tick,
                        ..AirHeader::default()
                    }
                })?;
                Ok(())
            }
            SenseSink::Iceoryx2(ports) => {
                for (i, port) in ports.iter().enumerate() {
                    if !alive.get(i).copied().unwrap_or(false) {
                        continue;
                    }
                    let mut sample =
                        port.publisher
                            .loan_uninit()
                            .map_err(|source| TransportError::Loan {
                                service: ServiceId::Sense(i as u32),
                                source,
                            })?;
                    let p = sample.payload_mut().as_mut_ptr();
                    // SAFETY: Sense is plain old data, valid when zeroed; the loaned slot is
                    // initialised shared memory (tmpfs); we zero the fixed part (the lists are
                    // written up to their counts) and then write through a reference.
                    let s = unsafe {
                        std::ptr::write_bytes(p as *mut u8, 0, SENSE_FIXED_BYTES);
                        &mut *p
                    };
                    sense(i as u32, s);
                    // SAFETY: fully initialised above.
                    let sample = unsafe { sample.assume_init() };
                    sample.send().map_err(|source| TransportError::Send {
                        service: ServiceId::Sense(i as u32),
                        source,
                    })?;
                }
                Ok(())
            }
        }
    }

    /// Robot `robot`'s agent is dead or replaced: its hold on the ring (if any) is free.
    pub fn release_robot(&self, robot: u32) {
        if let SenseSink::Ring { writer, .. } = self {
            writer.release_robot(robot);
        }
    }
}

fn zero_fixed(s: &mut Sense) {
    // SAFETY: Sense is plain old data, valid when zeroed; its first SENSE_FIXED_BYTES are
    // its fixed fields.
    unsafe { std::ptr::write_bytes(s as *mut Sense as *mut u8, 0, SENSE_FIXED_BYTES) };
}

/// An agent's side of its Sense frames.
pub enum SenseSource {
    Ring {
        reader: AirReader,
        robot: u32,
        /// The tick of the last frame handed out (a frame is handed out once, as iceoryx2's
        /// buffer of one does).
        last: Option<u64>,
    },
    Iceoryx2 {
        subscriber: Subscriber<ipc::Service, Sense, ()>,
        robot: u32,
        _service: SenseService,
    },
}

/// A Sense frame as an agent got it.
pub enum SenseGot {
    /// Copied from the ring into the frame the caller passed.
    Copied,
    /// The iceoryx2 sample, read in place.
    Sample(iceoryx2::sample::Sample<ipc::Service, Sense, ()>),
}

impl SenseSource {
    /// Opens the run's Sense transport (`runtime.sense`) for robot `robot`'s agent.
    pub fn open(
        node: &Node<ipc::Service>,
        prefix: &str,
        sc: &Scenario,
        robot: u32,
    ) -> TransportResult<Self> {
        Ok(match sc.runtime.sense {
            FrameTransport::Ring => SenseSource::Ring {
                reader: AirReader::open_named(prefix, SENSE_RING, robot)?,
                robot,
                last: None,
            },
            FrameTransport::Iceoryx2 => {
                let service = sense_service(node, robot, false)?;
                let subscriber = service
                    .subscriber_builder()
                    .buffer_size(1)
                    .create()
                    .map_err(|source| TransportError::Subscriber {
                        service: ServiceId::Sense(robot),
                        source,
                    })?;
                SenseSource::Iceoryx2 {
                    subscriber,
                    robot,
                    _service: service,
                }
            }
        })
    }

    /// The newest frame not handed out yet (None: none since the last call, or none for
    /// this robot). From the ring it is copied into `into` (the fixed fields and the lists up
    /// to their counts); a record that does not parse counts as none (the world wrote it, so
    /// it cannot happen while the world is sound).
    pub fn receive(&mut self, into: &mut Sense) -> TransportResult<Option<SenseGot>> {
        match self {
            SenseSource::Ring {
                reader,
                robot,
                last,
            } => {
                let Some(read) = reader.read()? else {
                    return Ok(None);
                };
                if *last == Some(read.tick) {
                    return Ok(None);
                }
                *last = Some(read.tick);
                Ok(match unpack_into(read.bytes(), *robot, into) {
                    Ok(true) => Some(SenseGot::Copied),
                    _ => None,
                })
            }
            SenseSource::Iceoryx2 {
                subscriber, robot, ..
            } => Ok(subscriber
                .receive()
                .map_err(|source| TransportError::Receive {
                    service: ServiceId::Sense(*robot),
                    source,
                })?
                .map(SenseGot::Sample)),
        }
    }
}
