//! `recording.bin`: a bincode stream of one header and one record per tick.
//!
//! Holds no wall-clock values, so lock-step runs with the same scenario and seed give
//! byte-identical files whatever the executor and the OS scheduling.

use crate::layer::Mark;
use crate::radio::RadioCounters;
use serde::{Deserialize, Serialize};
use std::io::{BufReader, BufWriter, Read, Write};

/// Version 3: the header, then one [`TickRecord`] per tick. (Versions 1 and 2 had the link
/// design's radio counters, with `dropped_unlinked`; the shared medium's counters replaced
/// them: see [`RadioCounters`].)
pub const RECORDING_VERSION: u32 = 3;
/// Version 4: as version 3, each TickRecord followed by its [`TickExtra`]. A run writes it
/// when it has something to put there (robots with a body); other runs keep version 3.
pub const RECORDING_VERSION_EXTRA: u32 = 4;
/// Version 5: as version 4, each TickExtra followed by the tick's [`TickLayer`] (the mission's
/// marks, for the viewer). A run writes it when its mission has a layer (search: targets).
pub const RECORDING_VERSION_LAYER: u32 = 5;
/// Version 6: as version 5, each TickLayer followed by the tick's radio counters in payload
/// bytes (a [`RadioCounters`] whose every field counts bytes: `TickRecord::radio_bytes`).
/// Every run writes it (the TickExtra and TickLayer of a run without them cost a byte each).
pub const RECORDING_VERSION_BYTES: u32 = 6;
/// The oldest version this reader understands.
pub const RECORDING_VERSION_OLDEST: u32 = 3;
/// Version 7: as version 6, each tick's byte counters followed by its [`TickDeliveries`] (who
/// heard whom). Opt-in (`runtime.record_deliveries`, `up --record-deliveries`): other runs
/// write version 6.
pub const RECORDING_VERSION_DELIVERIES: u32 = 7;

/// Clearances of robot bodies at one tick (robots with `robot.radius` > 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BodyFigures {
    /// Smallest gap between two robots' discs (centre distance - 2r; negative: overlap),
    /// over every pair (dead robots included: they stand where they died). Infinite with
    /// fewer than two robots.
    pub min_robot_clearance: f64,
    /// Smallest gap between a robot's disc and an obstacle or wall (negative: overlap).
    pub min_obstacle_clearance: f64,
    /// Pairs of robots whose discs overlap (centre distance < 2r).
    pub overlapping_pairs: u32,
    /// Robots whose disc overlaps an obstacle or leaves the arena.
    pub obstacle_overlaps: u32,
}

impl Default for BodyFigures {
    fn default() -> Self {
        BodyFigures {
            min_robot_clearance: f64::INFINITY,
            min_obstacle_clearance: f64::INFINITY,
            overlapping_pairs: 0,
            obstacle_overlaps: 0,
        }
    }
}

/// What a version-2 recording adds to each tick.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TickExtra {
    pub body: Option<BodyFigures>,
}

/// What a version-5 recording adds after each tick's TickExtra: the mission's layer at the end
/// of the tick (`Mission::live_layer`), or None when it is the previous tick's (a search's
/// targets change only when one is found, so most ticks cost one byte).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TickLayer {
    pub marks: Option<Vec<Mark>>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecordingHeader {
    pub version: u32,
    pub robots: u32,
    pub seed: u64,
    /// The resolved scenario, as TOML.
    pub scenario: String,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum RejectReason {
    /// NaN or infinite velocity.
    NotFinite,
    /// Speed above robot.v_max.
    TooFast,
    /// The frame names another robot than the one whose service carried it.
    WrongRobot,
    /// The frame is for another tick.
    WrongTick,
    /// More destinations than radio.max_messages_per_tick, or an unknown destination id.
    BadRadioReport,
    /// Turn rate above the unicycle's robot.kinematics.w_max.
    TurnTooFast,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Event {
    /// The robot's process died (or went silent past the deadline); it stands still from now on.
    RobotDied { robot: u32, cause: String },
    /// A new agent process drives the robot again (policy "restart").
    RobotRestarted { robot: u32 },
    /// The robot's Action frame was rejected; it stood still this tick.
    ActionRejected { robot: u32, reason: RejectReason },
    /// The robot's step would have crossed an obstacle or left the arena; it stopped short.
    MoveBlocked { robot: u32 },
    /// The mission counts `entity` as done thanks to `robot` (search: the robot came within
    /// the found distance of the target).
    EntityDone { entity: u32, robot: u32 },
    /// Behaviour-declared event flags.
    Declared { robot: u32, flags: u32 },
    /// Real-time mode (`runtime.realtime_hz`): the robot's action for this tick missed its
    /// deadline; it kept its last command.
    DeadlineMissed { robot: u32 },
    /// The mission's progress figure is now `done` of `total`: pushed when it changes by a
    /// mission whose figure is not a count of `EntityDone` events (formation: robots in
    /// place of live robots, which goes down as well as up), so a viewer of the recording
    /// shows what the terminal showed. (Last variant: older recordings read unchanged.)
    Progress { done: u32, total: u32 },
}

/// An event's fields as the exports and the Python reader show them: one place, so the CSV
/// export (`orchestrator export --format events`) and `swarm.Recording.events` agree.
impl Event {
    /// The snake_case name (robot_died, robot_restarted, action_rejected, move_blocked,
    /// entity_done, declared, deadline_missed, progress).
    pub fn name(&self) -> &'static str {
        match self {
            Event::RobotDied { .. } => "robot_died",
            Event::RobotRestarted { .. } => "robot_restarted",
            Event::ActionRejected { .. } => "action_rejected",
            Event::MoveBlocked { .. } => "move_blocked",
            Event::EntityDone { .. } => "entity_done",
            Event::Declared { .. } => "declared",
            Event::DeadlineMissed { .. } => "deadline_missed",
            Event::Progress { .. } => "progress",
        }
    }
    /// The robot it is about (None: the mission's own, its progress).
    pub fn robot(&self) -> Option<u32> {
        match self {
            Event::RobotDied { robot, .. }
            | Event::RobotRestarted { robot }
            | Event::ActionRejected { robot, .. }
            | Event::MoveBlocked { robot }
            | Event::EntityDone { robot, .. }
            | Event::Declared { robot, .. }
            | Event::DeadlineMissed { robot } => Some(*robot),
            Event::Progress { .. } => None,
        }
    }
    /// The mission entity (entity_done only).
    pub fn entity(&self) -> Option<u32> {
        match self {
            Event::EntityDone { entity, .. } => Some(*entity),
            _ => None,
        }
    }
    /// The cause of a death, the reason of a rejection, the flags of a declaration, the
    /// progress as "done of total"; empty for the others.
    pub fn detail(&self) -> String {
        match self {
            Event::RobotDied { cause, .. } => cause.clone(),
            Event::ActionRejected { reason, .. } => format!("{reason:?}"),
            Event::Declared { flags, .. } => format!("flags {flags:#x}"),
            Event::Progress { done, total } => format!("{done} of {total}"),
            _ => String::new(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TickRecord {
    pub tick: u64,
    /// Position and heading of every robot after this tick's actions.
    pub poses: Vec<[f64; 3]>,
    /// 1 for a live robot, 0 for a dead one.
    pub alive: Vec<u8>,
    /// Each robot's display state this tick (Action.events & STATE_MASK).
    pub states: Vec<u8>,
    pub events: Vec<Event>,
    /// The medium's counts of the messages sent at this tick (offered and dropped), the
    /// outcome of those due at it (delivered, malformed, receiver dead), and what is in flight
    /// after it.
    pub radio: RadioCounters,
    /// The same counters in payload bytes: each (message, receiver) pair counts its message's
    /// length. Version 6: written after the TickLayer; zero when read from older versions.
    #[serde(skip)]
    pub radio_bytes: RadioCounters,
    /// Version 4 only: written after the record, not inside it.
    #[serde(skip)]
    pub extra: Option<TickExtra>,
    /// Version 5 only: the mission's marks at the end of this tick (written after the
    /// TickExtra as a [`TickLayer`]; read back whole, unchanged ticks filled in).
    #[serde(skip)]
    pub layer: Option<Vec<Mark>>,
    /// Version 6 only: the messages each robot was handed this tick (written after the
    /// TickLayer).
    #[serde(skip)]
    pub deliveries: Option<TickDeliveries>,
}

fn cfg() -> bincode::config::Configuration {
    bincode::config::standard()
}

pub struct RecordingWriter<W: Write> {
    out: BufWriter<W>,
    /// Version 4: a TickExtra follows each record.
    extra: bool,
    /// Version 5: a TickLayer follows each TickExtra; the last marks written.
    layer: Option<Vec<Mark>>,
    /// Version 6: the radio's byte counters follow each TickLayer.
    bytes: bool,
    /// Flush after every tick (a live viewer reads the file as it grows).
    flush_each_tick: bool,
    /// Version 6: a TickDeliveries follows each TickLayer.
    deliveries: bool,
}

impl<W: Write> RecordingWriter<W> {
    pub fn new(w: W, header: &RecordingHeader) -> std::io::Result<Self> {
        let mut out = BufWriter::new(w);
        bincode::serde::encode_into_std_write(header, &mut out, cfg())
            .map_err(std::io::Error::other)?;
        Ok(RecordingWriter {
            out,
            extra: header.version >= RECORDING_VERSION_EXTRA,
            layer: (header.version >= RECORDING_VERSION_LAYER).then(Vec::new),
            bytes: header.version >= RECORDING_VERSION_BYTES,
            flush_each_tick: false,
            deliveries: header.version >= RECORDING_VERSION_DELIVERIES,
        })
    }
    /// Every tick reaches the file when pushed (`orchestrator up --view`); otherwise the
    /// buffer fills first. The bytes are the same.
    pub fn flush_each_tick(&mut self, on: bool) {
        self.flush_each_tick = on;
    }
    pub fn push(&mut self, rec: &TickRecord) -> std::io::Result<()> {
        self.push_with_layer(rec, rec.layer.as_deref())
    }
    /// [`push`](Self::push) with the tick's layer given apart from the record (`None`: no
    /// marks this tick).
    pub fn push_with_layer(
        &mut self,
        rec: &TickRecord,
        marks: Option<&[Mark]>,
    ) -> std::io::Result<()> {
        bincode::serde::encode_into_std_write(rec, &mut self.out, cfg())
            .map_err(std::io::Error::other)?;
        if self.extra {
            let extra = rec.extra.clone().unwrap_or_default();
            bincode::serde::encode_into_std_write(&extra, &mut self.out, cfg())
                .map_err(std::io::Error::other)?;
        }
        if let Some(last) = self.layer.as_mut() {
            let now = marks.unwrap_or(&[]);
            // The first tick always carries its marks; later ones only when they changed.
            let changed = rec.tick == 0 || now != &last[..];
            let out: Option<&[Mark]> = changed.then_some(now);
            bincode::serde::encode_into_std_write(out, &mut self.out, cfg())
                .map_err(std::io::Error::other)?;
            if changed {
                last.clear();
                last.extend_from_slice(now);
            }
        }
        if self.bytes {
            bincode::serde::encode_into_std_write(rec.radio_bytes, &mut self.out, cfg())
                .map_err(std::io::Error::other)?;
        }
        if self.deliveries {
            let d = rec.deliveries.as_ref().unwrap_or(&NO_DELIVERIES);
            bincode::serde::encode_into_std_write(d, &mut self.out, cfg())
                .map_err(std::io::Error::other)?;
        }
        if self.flush_each_tick {
            self.out.flush()?;
        }
        Ok(())
    }
    pub fn finish(mut self) -> std::io::Result<()> {
        self.out.flush()
    }
}

/// Reads a whole recording.
pub fn read_recording<R: Read>(r: R) -> std::io::Result<(RecordingHeader, Vec<TickRecord>)> {
    let mut inp = BufReader::new(r);
    let header = read_finished_header(&mut inp)?;
    let mut ticks = Vec::new();
    let mut reader = TickReader::new(&header);
    while let Some(t) = reader.next(&mut inp)? {
        ticks.push(t);
    }
    Ok((header, ticks))
}

/// Reads the header of a finished recording, refusing versions this build cannot read; the
/// ticks follow, one at a time, from a [`TickReader`].
pub fn read_finished_header<R: Read>(r: &mut R) -> std::io::Result<RecordingHeader> {
    let header: RecordingHeader =
        bincode::serde::decode_from_std_read(r, cfg()).map_err(std::io::Error::other)?;
    if header.version < RECORDING_VERSION_OLDEST {
        return Err(std::io::Error::other(format!(
            "recording version {} is older than {RECORDING_VERSION_OLDEST} (the link design's radio counters): \
             re-run the scenario to record it again",
            header.version
        )));
    }
    Ok(header)
}

/// Reads the header of a recording (a live run's file, still growing).
pub fn read_header<R: Read>(r: &mut R) -> std::io::Result<RecordingHeader> {
    bincode::serde::decode_from_std_read(r, cfg()).map_err(std::io::Error::other)
}

/// Reads tick records one at a time after the header, filling in each tick's layer.
pub struct TickReader {
    extra: bool,
    layer: Option<Vec<Mark>>,
    bytes: bool,
    deliveries: bool,
}

impl TickReader {
    pub fn new(header: &RecordingHeader) -> TickReader {
        TickReader {
            extra: header.version >= RECORDING_VERSION_EXTRA,
            layer: (header.version >= RECORDING_VERSION_LAYER).then(Vec::new),
            bytes: header.version >= RECORDING_VERSION_BYTES,
            deliveries: header.version >= RECORDING_VERSION_DELIVERIES,
        }
    }

    /// The next tick, None at the end of the stream (a record cut short counts as the end).
    pub fn next<R: Read>(&mut self, inp: &mut R) -> std::io::Result<Option<TickRecord>> {
        let eof = |e: &bincode::error::DecodeError| match e {
            bincode::error::DecodeError::UnexpectedEnd { .. } => true,
            bincode::error::DecodeError::Io { inner, .. } => {
                inner.kind() == std::io::ErrorKind::UnexpectedEof
            }
            _ => false,
        };
        let mut t = match bincode::serde::decode_from_std_read::<TickRecord, _, _>(inp, cfg()) {
            Ok(t) => t,
            Err(e) if eof(&e) => return Ok(None),
            Err(e) => return Err(std::io::Error::other(e)),
        };
        if self.extra {
            match bincode::serde::decode_from_std_read(inp, cfg()) {
                Ok(x) => t.extra = Some(x),
                Err(e) if eof(&e) => return Ok(None),
                Err(e) => return Err(std::io::Error::other(e)),
            }
        }
        if let Some(last) = self.layer.as_mut() {
            match bincode::serde::decode_from_std_read::<Option<Vec<Mark>>, _, _>(inp, cfg()) {
                Ok(Some(m)) => *last = m,
                Ok(None) => {}
                Err(e) if eof(&e) => return Ok(None),
                Err(e) => return Err(std::io::Error::other(e)),
            }
            t.layer = Some(last.clone());
        }
        if self.bytes {
            match bincode::serde::decode_from_std_read(inp, cfg()) {
                Ok(b) => t.radio_bytes = b,
                Err(e) if eof(&e) => return Ok(None),
                Err(e) => return Err(std::io::Error::other(e)),
            }
        }
        if self.deliveries {
            match bincode::serde::decode_from_std_read(inp, cfg()) {
                Ok(d) => t.deliveries = Some(d),
                Err(e) if eof(&e) => return Ok(None),
                Err(e) => return Err(std::io::Error::other(e)),
            }
        }
        Ok(Some(t))
    }
}

/// One message a robot was handed at a tick (version 7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Heard {
    pub sender: u32,
    /// The sender's sequence number of the message.
    pub seq: u32,
    /// Payload bytes (the header not counted).
    pub bytes: u32,
}

/// What a version-6 recording adds after each tick's TickLayer: the messages the medium handed
/// each robot at this tick (those due now: sent `1 + radio.delay_ticks` ticks earlier), for
/// the viewer's "what it heard that tick". Their count over all robots is the tick's
/// `delivered + malformed`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TickDeliveries {
    /// Index = receiver: its messages in (sender, seq) order. Empty for a robot that was dead
    /// or sent no valid action this tick (its messages count as `receiver_dead`).
    pub heard: Vec<Vec<Heard>>,
    /// (robot, count) of the receivers that reported messages of their list as malformed
    /// (the agent reports a count, not which).
    pub malformed: Vec<(u32, u32)>,
}

/// A version-6 tick whose record carries no deliveries writes these (nothing heard).
static NO_DELIVERIES: TickDeliveries = TickDeliveries {
    heard: Vec::new(),
    malformed: Vec::new(),
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recording_round_trips() {
        let h = RecordingHeader {
            version: RECORDING_VERSION,
            robots: 2,
            seed: 3,
            scenario: "x".into(),
        };
        let t = TickRecord {
            tick: 0,
            poses: vec![[1.0, 2.0, 0.5], [3.0, 4.0, 0.0]],
            alive: vec![1, 0],
            states: vec![0, 1],
            events: vec![
                Event::MoveBlocked { robot: 1 },
                Event::RobotDied {
                    robot: 1,
                    cause: "SIGKILL".into(),
                },
            ],
            radio: RadioCounters {
                offered: 5,
                ..Default::default()
            },
            radio_bytes: RadioCounters::default(),
            extra: None,
            layer: None,
            deliveries: None,
        };
        let mut buf = Vec::new();
        let mut w = RecordingWriter::new(&mut buf, &h).unwrap();
        w.push(&t).unwrap();
        w.push(&t).unwrap();
        w.finish().unwrap();
        let (h2, ts) = read_recording(&buf[..]).unwrap();
        assert_eq!(h2, h);
        assert_eq!(ts, vec![t.clone(), t.clone()]);
        // Version 2: each record's extra comes back; version 1 has none to give.
        let h2 = RecordingHeader {
            version: RECORDING_VERSION_EXTRA,
            ..h
        };
        let mut t2 = t.clone();
        t2.extra = Some(TickExtra {
            body: Some(BodyFigures {
                min_robot_clearance: -0.5,
                min_obstacle_clearance: 2.0,
                overlapping_pairs: 1,
                obstacle_overlaps: 0,
            }),
        });
        let mut buf2 = Vec::new();
        let mut w = RecordingWriter::new(&mut buf2, &h2).unwrap();
        w.push(&t2).unwrap();
        w.push(&t2).unwrap();
        w.finish().unwrap();
        assert_eq!(read_recording(&buf2[..]).unwrap().1, vec![t2.clone(), t2]);
        assert!(buf2.len() > buf.len());
    }

    #[test]
    fn version_6_carries_the_byte_counters_and_older_versions_read_them_as_zero() {
        let h = RecordingHeader {
            version: RECORDING_VERSION_BYTES,
            robots: 1,
            seed: 0,
            scenario: String::new(),
        };
        let t = TickRecord {
            tick: 0,
            poses: vec![[0.0; 3]],
            alive: vec![1],
            states: vec![0],
            events: vec![],
            radio: RadioCounters {
                offered: 2,
                delivered: 2,
                ..Default::default()
            },
            radio_bytes: RadioCounters {
                offered: 300,
                delivered: 200,
                dropped_loss: 100,
                ..Default::default()
            },
            extra: Some(TickExtra::default()),
            layer: Some(vec![]),
            deliveries: None,
        };
        let mut buf = Vec::new();
        let mut w = RecordingWriter::new(&mut buf, &h).unwrap();
        w.push(&t).unwrap();
        w.push(&TickRecord {
            tick: 1,
            ..t.clone()
        })
        .unwrap();
        w.finish().unwrap();
        let (_, back) = read_recording(&buf[..]).unwrap();
        assert_eq!(
            back,
            vec![
                t.clone(),
                TickRecord {
                    tick: 1,
                    ..t.clone()
                }
            ]
        );
        // The same tick in version 5: no bytes written, none read.
        let h5 = RecordingHeader {
            version: RECORDING_VERSION_LAYER,
            ..h
        };
        let mut buf5 = Vec::new();
        let mut w = RecordingWriter::new(&mut buf5, &h5).unwrap();
        w.push(&t).unwrap();
        w.finish().unwrap();
        let (_, back5) = read_recording(&buf5[..]).unwrap();
        assert_eq!(back5[0].radio_bytes, RadioCounters::default());
        assert_eq!(back5[0].radio, t.radio);
    }

    #[test]
    fn version_3_writes_a_layer_only_when_it_changes_and_reads_every_tick_whole() {
        let h = RecordingHeader {
            version: RECORDING_VERSION_LAYER,
            robots: 1,
            seed: 0,
            scenario: String::new(),
        };
        let disc = |fill: u8| Mark::Disc {
            at: [1.0, 2.0],
            px: 5,
            fill: [fill, 0, 0],
            outline: None,
        };
        let tick = |k: u64, m: Vec<Mark>| TickRecord {
            tick: k,
            poses: vec![[k as f64, 0.0, 0.0]],
            alive: vec![1],
            states: vec![0],
            events: vec![],
            radio: RadioCounters::default(),
            radio_bytes: RadioCounters::default(),
            extra: Some(TickExtra::default()),
            layer: Some(m),
            deliveries: None,
        };
        let ticks = vec![
            tick(0, vec![disc(1)]),
            tick(1, vec![disc(1)]),
            tick(2, vec![disc(2)]),
            tick(3, vec![]),
        ];
        let mut buf = Vec::new();
        let mut w = RecordingWriter::new(&mut buf, &h).unwrap();
        let mut sizes = vec![];
        for t in &ticks {
            w.push(t).unwrap();
            w.out.flush().unwrap();
            sizes.push(w.out.get_ref().len());
        }
        w.finish().unwrap();
        let (_, back) = read_recording(&buf[..]).unwrap();
        assert_eq!(back, ticks);
        // Tick 1 repeats tick 0's marks: one byte (None) instead of the disc; ticks 0 and 1
        // differ in nothing else of the same size (pose x 0.0 vs 1.0 are both 8 bytes).
        let t0 = sizes[0] - encoded_header_len(&h);
        let t1 = sizes[1] - sizes[0];
        let disc_bytes = bincode::serde::encode_to_vec(Some(vec![disc(1)]), cfg()).unwrap();
        assert_eq!(t0 - t1, disc_bytes.len() - 1);
        // A record cut anywhere reads as the end, not as an error, and not as a tick.
        for cut in sizes[1] + 1..sizes[2] {
            let (_, part) = read_recording(&buf[..cut]).unwrap();
            assert_eq!(part.len(), 2, "cut at {cut}");
        }
    }

    #[test]
    fn version_7_carries_each_ticks_deliveries_after_its_byte_counters() {
        let h = RecordingHeader {
            version: RECORDING_VERSION_DELIVERIES,
            robots: 3,
            seed: 0,
            scenario: String::new(),
        };
        let heard = |sender, seq, bytes| Heard { sender, seq, bytes };
        let tick = |k: u64, d: Option<TickDeliveries>| TickRecord {
            tick: k,
            poses: vec![[0.0; 3]; 3],
            alive: vec![1, 1, 0],
            states: vec![0; 3],
            events: vec![],
            radio: RadioCounters::default(),
            radio_bytes: RadioCounters::default(),
            extra: Some(TickExtra::default()),
            layer: Some(vec![]),
            deliveries: d,
        };
        let d1 = TickDeliveries {
            heard: vec![
                vec![heard(1, 7, 12)],
                vec![heard(0, 3, 4), heard(0, 4, 300)],
                vec![],
            ],
            malformed: vec![(1, 1)],
        };
        let ticks = vec![tick(0, Some(TickDeliveries::default())), tick(1, Some(d1))];
        let mut buf = Vec::new();
        let mut w = RecordingWriter::new(&mut buf, &h).unwrap();
        for t in &ticks {
            w.push(t).unwrap();
        }
        // A record without deliveries writes "nothing heard".
        w.push(&tick(2, None)).unwrap();
        w.finish().unwrap();
        let (_, back) = read_recording(&buf[..]).unwrap();
        assert_eq!(back[..2], ticks[..]);
        assert_eq!(back[2].deliveries, Some(TickDeliveries::default()));
        // Cut inside the last record's deliveries: two ticks.
        let (_, part) = read_recording(&buf[..buf.len() - 1]).unwrap();
        assert_eq!(part.len(), 2);
        // The same ticks in version 6 are smaller by exactly the deliveries.
        let mut buf5 = Vec::new();
        let h5 = RecordingHeader {
            version: RECORDING_VERSION_BYTES,
            ..h.clone()
        };
        let mut w = RecordingWriter::new(&mut buf5, &h5).unwrap();
        for t in &ticks {
            w.push(t).unwrap();
        }
        w.push(&tick(2, None)).unwrap();
        w.finish().unwrap();
        let d_bytes: usize = [
            TickDeliveries::default(),
            ticks[1].deliveries.clone().unwrap(),
            TickDeliveries::default(),
        ]
        .iter()
        .map(|d| bincode::serde::encode_to_vec(d, cfg()).unwrap().len())
        .sum();
        assert_eq!(
            buf.len() - encoded_header_len(&h),
            buf5.len() - encoded_header_len(&h5) + d_bytes
        );
    }

    fn encoded_header_len(h: &RecordingHeader) -> usize {
        bincode::serde::encode_to_vec(h, cfg()).unwrap().len()
    }
}
