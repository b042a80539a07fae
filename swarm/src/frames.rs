//! Fixed-size `#[repr(C)]` frames that travel through iceoryx2 shared memory.
//!
//! Sense and Action are plain old data: no heap, no pointers, written in place into a loaned
//! sample and read in place by the receiver. Both executors pass exactly these structs, so the
//! in-process executor sees the same values (and the same rounding) as the processes.

use iceoryx2::prelude::*;

/// Most obstacle / wall boundary points in a Sense frame (the nearest when more are in range).
pub const MAX_OBSTACLE_POINTS: usize = 768;
/// Most mission entities in a Sense frame (whatever the mission lets a robot sense).
pub const MAX_ENTITIES: usize = 32;
/// Most robots a Sense frame lists as sensed by the robot's own sensors (with positions and
/// velocities, within `robot.neighbour_sensing_radius`; the nearest when more are in range).
pub const MAX_NEARBY: usize = 32;
/// Most radio messages one robot may send in one tick.
pub const MAX_SENT: usize = 16;
/// Destination of a broadcast.
pub const BROADCAST: u32 = u32::MAX;

/// Sense frame `run_state`.
pub const RUN_RUNNING: u32 = 0;
pub const RUN_STOPPING: u32 = 1;

/// A mission entity as a robot senses it: what it is (`kind`, named by the mission), which one
/// (`id`), and what the sensor gives: a position (`ENTITY_HAS_POS`), a value (an intensity, a
/// distance: the mission says which), or both.
#[derive(Debug, Clone, Copy, ZeroCopySend, PartialEq)]
#[type_name("swarm::Entity")]
#[repr(C)]
pub struct Entity {
    pub id: u32,
    /// The mission's kind of entity (each mission names its kinds).
    pub kind: u32,
    /// ENTITY_DONE_BY_YOU, ENTITY_HAS_POS.
    pub flags: u32,
    pub reserved: u32,
    /// Where the entity is, when the sensor gives it (`flags & ENTITY_HAS_POS`).
    pub pos: [f64; 2],
    /// The sensed value (an intensity, a distance: the mission says which).
    pub value: f64,
}

/// This robot completed the entity at the last move (reached it, took it: the mission says
/// what completing means); a one-off entry, the robot's arrival sensor.
pub const ENTITY_DONE_BY_YOU: u32 = 1;
/// The entry's `pos` holds the entity's position.
pub const ENTITY_HAS_POS: u32 = 2;

/// Another robot as this robot's own sensors see it (not the radio).
#[derive(Debug, Clone, Copy, ZeroCopySend, PartialEq)]
#[type_name("swarm::Nearby")]
#[repr(C)]
pub struct Nearby {
    pub robot: u32,
    pub reserved: u32,
    pub pos: [f64; 2],
    pub vel: [f64; 2],
}

/// World -> agent i, once per tick: everything robot i may know from its own sensors.
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[type_name("swarm::Sense")]
#[repr(C)]
pub struct Sense {
    pub tick: u64,
    pub robot: u32,
    pub run_state: u32,
    pub pos: [f64; 2],
    pub heading: f64,
    pub vel: [f64; 2],
    /// Live robots in the run (the robot's own count of the swarm, as a radio beacon would).
    pub alive_robots: u32,
    pub n_obstacle_points: u32,
    pub n_entities: u32,
    pub n_nearby: u32,
    /// Obstacle, wall and dead-robot points within the sensing radius, as a set: in no
    /// particular order, but the same order for the same positions (the nearest
    /// MAX_OBSTACLE_POINTS when more are in range).
    pub obstacle_points: [[f64; 2]; MAX_OBSTACLE_POINTS],
    pub entities: [Entity; MAX_ENTITIES],
    /// Live robots within `robot.neighbour_sensing_radius`, by robot id (the nearest
    /// MAX_NEARBY when more are in range).
    pub nearby: [Nearby; MAX_NEARBY],
}

/// Bytes of a Sense frame before its lists: what a writer zeroes before filling the lists up
/// to their counts.
pub const SENSE_FIXED_BYTES: usize = std::mem::offset_of!(Sense, obstacle_points);

impl Sense {
    /// An all-zero frame (every field of a Sense is valid when zero).
    pub fn zeroed() -> Box<Sense> {
        // SAFETY: Sense is repr(C) plain old data of integers and floats; all-zero is valid.
        unsafe {
            let layout = std::alloc::Layout::new::<Sense>();
            let p = std::alloc::alloc_zeroed(layout) as *mut Sense;
            assert!(!p.is_null());
            Box::from_raw(p)
        }
    }
    /// Writes every list in full with values derived from `x` (the largest frame, as the
    /// benchmarks send it); the fixed fields other than the counts are left as they are.
    pub fn fill_every_list(&mut self, x: f64) {
        self.n_obstacle_points = MAX_OBSTACLE_POINTS as u32;
        self.n_entities = MAX_ENTITIES as u32;
        self.n_nearby = MAX_NEARBY as u32;
        for (i, q) in self.obstacle_points.iter_mut().enumerate() {
            *q = [i as f64, x];
        }
        for (i, g) in self.entities.iter_mut().enumerate() {
            *g = Entity {
                id: i as u32,
                kind: 0,
                flags: 0,
                reserved: 0,
                pos: [x, i as f64],
                value: 1.0 / (1.0 + i as f64),
            };
        }
        for (i, g) in self.nearby.iter_mut().enumerate() {
            *g = Nearby {
                robot: i as u32,
                reserved: 0,
                pos: [x, i as f64],
                vel: [1.0, 0.0],
            };
        }
    }

    pub fn obstacle_points(&self) -> &[[f64; 2]] {
        &self.obstacle_points[..(self.n_obstacle_points as usize).min(MAX_OBSTACLE_POINTS)]
    }
    pub fn entities(&self) -> &[Entity] {
        &self.entities[..(self.n_entities as usize).min(MAX_ENTITIES)]
    }
    pub fn nearby(&self) -> &[Nearby] {
        &self.nearby[..(self.n_nearby as usize).min(MAX_NEARBY)]
    }
}

/// Agent i -> world, once per tick: the robot's command and what its radio did.
#[derive(Debug, Clone, Copy, ZeroCopySend, PartialEq)]
#[type_name("swarm::Action")]
#[repr(C)]
pub struct Action {
    pub tick: u64,
    pub robot: u32,
    /// Low 8 bits (STATE_MASK): the behaviour's display state (0 = STATE_DEFAULT; each
    /// behaviour names its own states), recorded per tick and used to colour trajectories.
    /// Higher bits: behaviour-declared event flags.
    pub events: u32,
    /// The motion command: (vx, vy) for holonomic robots, (v, w) for unicycles
    /// (`robot.kinematics`).
    pub cmd: [f64; 2],
    /// What the behaviour reports to the mission this tick (a robot's claim, as a real robot
    /// reports to a monitor: e.g. the slot it is heading for); the mission says what the
    /// numbers mean, other missions ignore them.
    pub report: [f64; 4],
    /// Messages sent this tick and their destinations (BROADCAST or a robot id).
    pub n_sent: u32,
    /// Messages due at this tick that the receiver's transport decoded (its inbox).
    pub radio_delivered: u32,
    /// Bytes of this tick's messages behind the Action in the act sample (`swarm::air`).
    pub radio_bytes: u32,
    /// Messages due at this tick that the receiver could not decode.
    pub radio_malformed: u32,
    pub sent_to: [u32; MAX_SENT],
}

impl Action {
    pub fn idle(tick: u64, robot: u32) -> Action {
        Action {
            tick,
            robot,
            events: 0,
            cmd: [0.0, 0.0],
            report: [0.0; 4],
            n_sent: 0,
            radio_delivered: 0,
            radio_bytes: 0,
            radio_malformed: 0,
            sent_to: [0; MAX_SENT],
        }
    }
}

impl Default for Action {
    /// An idle action of robot 0 at tick 0 (iceoryx2 wants a default user header).
    fn default() -> Self {
        Action::idle(0, 0)
    }
}

pub const STATE_MASK: u32 = 0xff;
/// The display state every behaviour starts in.
pub const STATE_DEFAULT: u32 = 0;

/// The fixed header in front of every radio message's bincode payload.
#[derive(Debug, Clone, Copy, ZeroCopySend, PartialEq)]
#[type_name("swarm::RadioHeader")]
#[repr(C)]
pub struct RadioHeader {
    pub sender: u32,
    pub dest: u32,
    pub tick: u64,
    pub seq: u32,
    pub len: u32,
    pub sender_pos: [f64; 2],
}

impl Default for RadioHeader {
    fn default() -> Self {
        RadioHeader {
            sender: 0,
            dest: BROADCAST,
            tick: 0,
            seq: 0,
            len: 0,
            sender_pos: [0.0; 2],
        }
    }
}

/// The user header of a Sense sample (`world/sense`, see `swarm::sense_pack`): the world's one
/// publication of every live robot's Sense record of `tick`.
#[derive(Debug, Clone, Copy, ZeroCopySend, Default, PartialEq)]
#[type_name("swarm::SenseHeader")]
#[repr(C)]
pub struct SenseHeader {
    /// The tick the frames are of.
    pub tick: u64,
    /// Robots in the sample's index (the run's agents, stations included).
    pub robots: u32,
    /// Bytes of the packed payload.
    pub bytes: u32,
}

/// The user header of an air sample (`radio/air`, see `swarm::air`): the world's one
/// publication of the messages due at `tick`.
#[derive(Debug, Clone, Copy, ZeroCopySend, Default, PartialEq)]
#[type_name("swarm::AirHeader")]
#[repr(C)]
pub struct AirHeader {
    /// The tick the messages are due at (the Sense frame's tick).
    pub tick: u64,
    /// The tick they were sent at.
    pub sent_tick: u64,
    pub robots: u32,
    pub messages: u32,
    /// (message, receiver) pairs listed.
    pub index_len: u32,
    pub payload_bytes: u32,
}

/// One message of an air sample: its header (sender, destination, send tick, seq, length, the
/// sender's position at the send tick, as the world knows it) and its payload's offset in the
/// sample's payload area.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct AirEntry {
    pub header: RadioHeader,
    pub offset: u32,
    pub reserved: u32,
}

/// World -> observers (the orchestrator's progress bar), once per tick.
#[derive(Debug, Clone, Copy, ZeroCopySend, Default, PartialEq)]
#[type_name("swarm::WorldStatus")]
#[repr(C)]
pub struct WorldStatus {
    pub tick: u64,
    pub max_ticks: u64,
    pub alive: u32,
    pub dead: u32,
    pub finished: u32,
    pub restarted: u32,
    /// The mission's progress: `progress_done` of `progress_total`; the mission names what it
    /// counts.
    pub progress_total: u32,
    pub progress_done: u32,
    pub offered: u64,
    pub delivered: u64,
    pub dropped_range: u64,
    pub dropped_loss: u64,
    /// Dropped by the medium for line of sight or bandwidth, or due at a dead receiver.
    pub dropped_other: u64,
    pub rejected_actions: u64,
    /// Real-time mode: deadlines missed so far, all robots (0 in lock-step).
    pub deadline_misses: u64,
}

/// Orchestrator -> world.
#[derive(Debug, Clone, Copy, ZeroCopySend, PartialEq)]
#[type_name("swarm::Control")]
#[repr(C)]
pub struct Control {
    pub kind: u32,
    pub robot: u32,
    /// For ROBOT_DIED: CLOCK_MONOTONIC microseconds when the orchestrator reaped the process.
    pub value: u64,
    /// For ROBOT_DIED: the last tick the orchestrator had seen when it reaped the process.
    pub tick: u64,
    /// For ROBOT_DIED: the process's wait status (waitpid), for the fault's cause
    /// (`swarm::agent::exit_cause`).
    pub status: i32,
    pub reserved: u32,
}

pub const CONTROL_ROBOT_DIED: u32 = 1;
pub const CONTROL_STOP: u32 = 2;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_have_fixed_c_layout() {
        // The layout is part of the wire format between processes: pin it.
        assert_eq!(std::mem::size_of::<RadioHeader>(), 40);
        assert_eq!(std::mem::size_of::<AirEntry>(), 48);
        assert_eq!(std::mem::size_of::<AirHeader>(), 32);
        assert_eq!(std::mem::align_of::<Sense>(), 8);
        assert_eq!(SENSE_FIXED_BYTES, 72);
        assert_eq!(std::mem::size_of::<Entity>(), 40);
        assert_eq!(std::mem::size_of::<Nearby>(), 40);
        assert_eq!(
            std::mem::size_of::<Sense>(),
            SENSE_FIXED_BYTES + 16 * MAX_OBSTACLE_POINTS + 40 * MAX_ENTITIES + 40 * MAX_NEARBY
        );
        assert_eq!(std::mem::size_of::<Action>(), 80 + 4 * MAX_SENT);
    }

    #[test]
    fn zeroed_sense_has_empty_lists() {
        let s = Sense::zeroed();
        assert!(s.obstacle_points().is_empty());
        assert!(s.entities().is_empty());
        assert!(s.nearby().is_empty());
    }

    #[test]
    fn list_accessors_clamp_corrupt_counts() {
        let mut s = Sense::zeroed();
        s.n_nearby = u32::MAX;
        assert_eq!(s.nearby().len(), MAX_NEARBY);
    }
}

#[cfg(test)]
mod protocol_tests {
    use super::*;
    use std::mem::{offset_of, size_of};

    /// The layouts docs/protocol.md gives, byte for byte: a change here is a change of the
    /// protocol every agent program speaks, and must change the page too.
    #[test]
    fn the_protocol_documents_layouts() {
        assert_eq!(size_of::<SenseHeader>(), 16);
        assert_eq!(
            [
                offset_of!(SenseHeader, tick),
                offset_of!(SenseHeader, robots),
                offset_of!(SenseHeader, bytes)
            ],
            [0, 8, 12]
        );
        assert_eq!(size_of::<Sense>(), 14_920);
        assert_eq!(SENSE_FIXED_BYTES, 72);
        assert_eq!(
            [
                offset_of!(Sense, tick),
                offset_of!(Sense, robot),
                offset_of!(Sense, run_state),
                offset_of!(Sense, pos),
                offset_of!(Sense, heading),
                offset_of!(Sense, vel),
                offset_of!(Sense, alive_robots),
                offset_of!(Sense, n_obstacle_points),
                offset_of!(Sense, n_entities),
                offset_of!(Sense, n_nearby),
                offset_of!(Sense, obstacle_points),
                offset_of!(Sense, entities),
                offset_of!(Sense, nearby),
            ],
            [0, 8, 12, 16, 32, 40, 56, 60, 64, 68, 72, 12_360, 13_640]
        );
        assert_eq!(size_of::<Entity>(), 40);
        assert_eq!(
            [
                offset_of!(Entity, id),
                offset_of!(Entity, kind),
                offset_of!(Entity, flags),
                offset_of!(Entity, pos),
                offset_of!(Entity, value)
            ],
            [0, 4, 8, 16, 32]
        );
        assert_eq!(size_of::<Nearby>(), 40);
        assert_eq!(
            [
                offset_of!(Nearby, robot),
                offset_of!(Nearby, pos),
                offset_of!(Nearby, vel)
            ],
            [0, 8, 24]
        );
        assert_eq!(size_of::<AirHeader>(), 32);
        assert_eq!(
            [
                offset_of!(AirHeader, tick),
                offset_of!(AirHeader, sent_tick),
                offset_of!(AirHeader, robots),
                offset_of!(AirHeader, messages),
                offset_of!(AirHeader, index_len),
                offset_of!(AirHeader, payload_bytes),
            ],
            [0, 8, 16, 20, 24, 28]
        );
        assert_eq!(size_of::<AirEntry>(), 48);
        assert_eq!(offset_of!(AirEntry, offset), 40);
        assert_eq!(size_of::<RadioHeader>(), 40);
        assert_eq!(
            [
                offset_of!(RadioHeader, sender),
                offset_of!(RadioHeader, dest),
                offset_of!(RadioHeader, tick),
                offset_of!(RadioHeader, seq),
                offset_of!(RadioHeader, len),
                offset_of!(RadioHeader, sender_pos),
            ],
            [0, 4, 8, 16, 20, 24]
        );
        assert_eq!(size_of::<Action>(), 144);
        assert_eq!(
            [
                offset_of!(Action, tick),
                offset_of!(Action, robot),
                offset_of!(Action, events),
                offset_of!(Action, cmd),
                offset_of!(Action, report),
                offset_of!(Action, n_sent),
                offset_of!(Action, radio_delivered),
                offset_of!(Action, radio_bytes),
                offset_of!(Action, radio_malformed),
                offset_of!(Action, sent_to),
            ],
            [0, 8, 12, 16, 32, 64, 68, 72, 76, 80]
        );
    }
}
