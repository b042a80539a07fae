//! What crosses hosts (docs/protocol.md section 9): the Zenoh key expressions of a run across
//! hosts and the layout of its messages. One message each way per tick and remote host: the
//! world's host sends [`Down::Tick`] (that host's robots' Sense records, packed as in
//! `world/sense`, and the tick's whole air), the host answers [`Up::Batch`] (its robots'
//! Actions with their message areas). The rest are rare: the run's start, attaches, deaths,
//! kill orders, the end.
//!
//! Layout: a kind byte, then the fields little-endian (native on the supported x86-64 and
//! aarch64), the bulk bytes as they lie in the iceoryx2 samples.

use swarm::frames::{Action, AirHeader};

/// The liveliness token of host `name`'s proxy: it exists while the proxy lives.
pub fn token_key(name: &str) -> String {
    format!("swarm/hosts/{name}")
}

/// Every host's liveliness token.
pub const TOKENS: &str = "swarm/hosts/*";

/// The world host's liveliness token: a proxy whose world is gone ends its part of the run.
pub const WORLD_TOKEN: &str = "swarm/world";

/// World's host -> host `name`.
pub fn down_key(name: &str) -> String {
    format!("swarm/hosts/{name}/down")
}

/// Host `name` -> world's host.
pub fn up_key(name: &str) -> String {
    format!("swarm/hosts/{name}/up")
}

/// Every host's messages to the world's host.
pub const UPS: &str = "swarm/hosts/*/up";

/// The host name in a key of [`token_key`] or [`up_key`].
pub fn host_of(key: &str) -> Option<&str> {
    key.strip_prefix("swarm/hosts/")?.split('/').next()
}

/// Why a message could not be read.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum WireError {
    #[error("message of {len} bytes is too short for its kind {kind}")]
    Short { kind: u8, len: usize },
    #[error("unknown message kind {0}")]
    Kind(u8),
    #[error("the run's start message is not valid: {0}")]
    Start(String),
}

/// World's host -> a remote host.
#[derive(Debug, Clone, PartialEq)]
pub enum Down {
    /// The run starts: its id, its resolved scenario (TOML) and this host's robots.
    Start {
        run_id: String,
        scenario: String,
        robots: Vec<u32>,
    },
    /// Tick `tick` is released: the host's live robots' Sense records (a `world/sense`
    /// payload), and the air due at the tick (header and payload).
    Tick {
        tick: u64,
        sense: Vec<u8>,
        air_header: AirHeader,
        air: Vec<u8>,
    },
    /// SIGKILL robot `robot`'s agent with attach number `attach`, if it still runs.
    Kill { robot: u32, attach: u64 },
    /// The run is over.
    Stop,
}

/// A remote host -> the world's host.
#[derive(Debug, Clone, PartialEq)]
pub enum Up {
    /// The host made its local services and started its agents.
    Ready,
    /// One more agent of robot `robot` attached on the host.
    Attached { robot: u32 },
    /// Robot `robot`'s agent died (reaped on the host); `attached`: it had attached;
    /// `status`: its wait status (waitpid), for the fault's cause.
    Died {
        robot: u32,
        attached: bool,
        status: i32,
    },
    /// The host's robots' actions of tick `tick` (a robot missing gives no action).
    Batch { tick: u64, acts: Vec<Act> },
    /// The host cannot run its part (its message); the world's host stops the run.
    Failed(String),
}

/// One robot's action of a tick as it crosses: the Action and the used message area.
#[derive(Debug, Clone, PartialEq)]
pub struct Act {
    pub robot: u32,
    pub action: Action,
    pub area: Vec<u8>,
}

const START: u8 = 1;
const TICK: u8 = 2;
const KILL: u8 = 3;
const STOP: u8 = 4;
const READY: u8 = 11;
const ATTACHED: u8 = 12;
const DIED: u8 = 13;
const BATCH: u8 = 14;
const FAILED: u8 = 15;

/// The bytes of a plain-old-data frame (`Action`, `AirHeader`: integers and floats, no
/// padding; docs/protocol.md gives their layouts).
fn pod_bytes<T: Copy>(v: &T) -> &[u8] {
    // SAFETY: T is one of this module's repr(C) frames without padding: every byte is
    // initialised.
    unsafe { std::slice::from_raw_parts(v as *const T as *const u8, std::mem::size_of::<T>()) }
}

/// A frame read back from its bytes (any bytes are a valid frame: integers and floats).
fn pod_read<T: Copy>(b: &[u8]) -> T {
    assert!(b.len() >= std::mem::size_of::<T>());
    // SAFETY: enough bytes (checked), read unaligned; every bit pattern is a valid T.
    unsafe { std::ptr::read_unaligned(b.as_ptr() as *const T) }
}

/// A cursor over a message's bytes that fails instead of reading past the end.
struct Reader<'a> {
    b: &'a [u8],
    at: usize,
    kind: u8,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], WireError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.b.len());
        let end = end.ok_or(WireError::Short {
            kind: self.kind,
            len: self.b.len(),
        })?;
        let s = &self.b[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u32(&mut self) -> Result<u32, WireError> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().expect("4")))
    }
    fn u64(&mut self) -> Result<u64, WireError> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().expect("8")))
    }
    fn bytes(&mut self) -> Result<&'a [u8], WireError> {
        let n = self.u32()? as usize;
        self.take(n)
    }
    fn string(&mut self) -> Result<String, WireError> {
        String::from_utf8(self.bytes()?.to_vec()).map_err(|e| WireError::Start(e.to_string()))
    }
}

fn put_bytes(out: &mut Vec<u8>, b: &[u8]) {
    out.extend_from_slice(&(b.len() as u32).to_le_bytes());
    out.extend_from_slice(b);
}

impl Down {
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::new();
        match self {
            Down::Start {
                run_id,
                scenario,
                robots,
            } => {
                out.push(START);
                put_bytes(&mut out, run_id.as_bytes());
                put_bytes(&mut out, scenario.as_bytes());
                out.extend_from_slice(&(robots.len() as u32).to_le_bytes());
                for r in robots {
                    out.extend_from_slice(&r.to_le_bytes());
                }
            }
            Down::Tick {
                tick,
                sense,
                air_header,
                air,
            } => {
                out.reserve(1 + 8 + 8 + sense.len() + 32 + air.len());
                out.push(TICK);
                out.extend_from_slice(&tick.to_le_bytes());
                put_bytes(&mut out, sense);
                out.extend_from_slice(pod_bytes(air_header));
                put_bytes(&mut out, air);
            }
            Down::Kill { robot, attach } => {
                out.push(KILL);
                out.extend_from_slice(&robot.to_le_bytes());
                out.extend_from_slice(&attach.to_le_bytes());
            }
            Down::Stop => out.push(STOP),
        }
        out
    }

    pub fn decode(b: &[u8]) -> Result<Down, WireError> {
        let kind = *b.first().ok_or(WireError::Short { kind: 0, len: 0 })?;
        let mut r = Reader { b, at: 1, kind };
        Ok(match kind {
            START => {
                let run_id = r.string()?;
                let scenario = r.string()?;
                let n = r.u32()? as usize;
                let robots = (0..n).map(|_| r.u32()).collect::<Result<_, _>>()?;
                Down::Start {
                    run_id,
                    scenario,
                    robots,
                }
            }
            TICK => {
                let tick = r.u64()?;
                let sense = r.bytes()?.to_vec();
                let air_header = pod_read(r.take(std::mem::size_of::<AirHeader>())?);
                let air = r.bytes()?.to_vec();
                Down::Tick {
                    tick,
                    sense,
                    air_header,
                    air,
                }
            }
            KILL => Down::Kill {
                robot: r.u32()?,
                attach: r.u64()?,
            },
            STOP => Down::Stop,
            k => return Err(WireError::Kind(k)),
        })
    }
}

impl Up {
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::new();
        match self {
            Up::Ready => out.push(READY),
            Up::Attached { robot } => {
                out.push(ATTACHED);
                out.extend_from_slice(&robot.to_le_bytes());
            }
            Up::Died {
                robot,
                attached,
                status,
            } => {
                out.push(DIED);
                out.extend_from_slice(&robot.to_le_bytes());
                out.push(*attached as u8);
                out.extend_from_slice(&status.to_le_bytes());
            }
            Up::Batch { tick, acts } => {
                out.push(BATCH);
                out.extend_from_slice(&tick.to_le_bytes());
                out.extend_from_slice(&(acts.len() as u32).to_le_bytes());
                for a in acts {
                    out.extend_from_slice(&a.robot.to_le_bytes());
                    out.extend_from_slice(pod_bytes(&a.action));
                    put_bytes(&mut out, &a.area);
                }
            }
            Up::Failed(m) => {
                out.push(FAILED);
                put_bytes(&mut out, m.as_bytes());
            }
        }
        out
    }

    pub fn decode(b: &[u8]) -> Result<Up, WireError> {
        let kind = *b.first().ok_or(WireError::Short { kind: 0, len: 0 })?;
        let mut r = Reader { b, at: 1, kind };
        Ok(match kind {
            READY => Up::Ready,
            ATTACHED => Up::Attached { robot: r.u32()? },
            DIED => Up::Died {
                robot: r.u32()?,
                attached: r.take(1)?[0] != 0,
                status: r.u32()? as i32,
            },
            BATCH => {
                let tick = r.u64()?;
                let n = r.u32()? as usize;
                let mut acts = Vec::with_capacity(n.min(b.len()));
                for _ in 0..n {
                    let robot = r.u32()?;
                    let action = pod_read(r.take(std::mem::size_of::<Action>())?);
                    let area = r.bytes()?.to_vec();
                    acts.push(Act {
                        robot,
                        action,
                        area,
                    });
                }
                Up::Batch { tick, acts }
            }
            FAILED => Up::Failed(String::from_utf8_lossy(r.bytes()?).into_owned()),
            k => return Err(WireError::Kind(k)),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn action(tick: u64) -> Action {
        Action {
            tick,
            robot: 7,
            events: 3,
            cmd: [0.5, -1.0],
            report: [1.0, 2.0, 3.0, 4.0],
            n_sent: 1,
            radio_delivered: 2,
            radio_bytes: 48,
            radio_malformed: 0,
            sent_to: [9; 16],
        }
    }

    #[test]
    fn every_message_reads_back_as_written() {
        let downs = [
            Down::Start {
                run_id: "r1".into(),
                scenario: "[run]\nrobots = 3\n".into(),
                robots: vec![1, 2],
            },
            Down::Tick {
                tick: 41,
                sense: vec![1, 2, 3],
                air_header: AirHeader {
                    tick: 41,
                    sent_tick: 40,
                    robots: 3,
                    messages: 1,
                    index_len: 2,
                    payload_bytes: 5,
                },
                air: vec![4; 17],
            },
            Down::Kill {
                robot: 2,
                attach: 3,
            },
            Down::Stop,
        ];
        for d in downs {
            assert_eq!(Down::decode(&d.encode()).unwrap(), d);
        }
        let ups = [
            Up::Ready,
            Up::Attached { robot: 4 },
            Up::Died {
                robot: 4,
                attached: true,
                status: 9,
            },
            Up::Batch {
                tick: 9,
                acts: vec![
                    Act {
                        robot: 1,
                        action: action(9),
                        area: vec![5; 48],
                    },
                    Act {
                        robot: 2,
                        action: action(9),
                        area: vec![],
                    },
                ],
            },
            Up::Failed("no agent binary".into()),
        ];
        for u in ups {
            assert_eq!(Up::decode(&u.encode()).unwrap(), u);
        }
    }

    #[test]
    fn a_cut_message_is_refused_not_read_past() {
        let b = Up::Batch {
            tick: 9,
            acts: vec![Act {
                robot: 1,
                action: action(9),
                area: vec![5; 48],
            }],
        }
        .encode();
        for cut in 0..b.len() {
            assert!(Up::decode(&b[..cut]).is_err(), "cut at {cut}");
        }
        assert_eq!(Down::decode(&[99]), Err(WireError::Kind(99)));
        assert_eq!(host_of("swarm/hosts/h1/up"), Some("h1"));
        assert_eq!(host_of(&token_key("h2")), Some("h2"));
    }
}
