//! Fixed-size `#[repr(C)]` frames that travel through iceoryx2 shared memory.
//!
//! Sense and Action are plain old data: no heap, no pointers, written in place into a loaned
//! sample and read in place by the receiver. Both executors pass exactly these structs, so the
//! in-process executor sees the same values (and the same rounding) as the processes.

use iceoryx2::prelude::*;

/// Most robots listed in a Sense frame's neighbour list (the agent's radio links).
pub const MAX_NEIGHBOURS: usize = 128;
/// Most obstacle / wall boundary points in a Sense frame (the nearest when more are in range).
pub const MAX_OBSTACLE_POINTS: usize = 768;
/// Most target signals in a Sense frame.
pub const MAX_SIGNALS: usize = 16;
/// Most radio messages one robot may send in one tick.
pub const MAX_SENT: usize = 16;
/// Destination of a broadcast.
pub const BROADCAST: u32 = u32::MAX;

/// Sense frame `run_state`.
pub const RUN_RUNNING: u32 = 0;
pub const RUN_STOPPING: u32 = 1;

#[derive(Debug, Clone, Copy, ZeroCopySend, PartialEq)]
#[type_name("swarm::Signal")]
#[repr(C)]
pub struct Signal {
    pub target: u32,
    /// SIGNAL_FOUND_BY_YOU: this robot came within the found distance of the target last tick
    /// (the target stops emitting; this entry is its arrival sensor, intensity 0).
    pub flags: u32,
    pub intensity: f64,
}

pub const SIGNAL_FOUND_BY_YOU: u32 = 1;

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
    pub n_neighbours: u32,
    pub n_obstacle_points: u32,
    pub n_signals: u32,
    /// Robots within comm_radius + link_margin, by robot id: whom the transport links to (at
    /// most radio.max_links; when more are in reach, those of the last list first, then the
    /// nearest others).
    pub neighbours: [u32; MAX_NEIGHBOURS],
    /// Obstacle, wall and dead-robot points within the sensing radius, as a set: in no
    /// particular order, but the same order for the same positions (the nearest
    /// MAX_OBSTACLE_POINTS when more are in range).
    pub obstacle_points: [[f64; 2]; MAX_OBSTACLE_POINTS],
    pub signals: [Signal; MAX_SIGNALS],
}

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
    pub fn neighbours(&self) -> &[u32] {
        &self.neighbours[..(self.n_neighbours as usize).min(MAX_NEIGHBOURS)]
    }
    pub fn obstacle_points(&self) -> &[[f64; 2]] {
        &self.obstacle_points[..(self.n_obstacle_points as usize).min(MAX_OBSTACLE_POINTS)]
    }
    pub fn signals(&self) -> &[Signal] {
        &self.signals[..(self.n_signals as usize).min(MAX_SIGNALS)]
    }
}

/// Agent i -> world, once per tick: the robot's command and what its radio did.
#[derive(Debug, Clone, Copy, ZeroCopySend, PartialEq)]
#[type_name("swarm::Action")]
#[repr(C)]
pub struct Action {
    pub tick: u64,
    pub robot: u32,
    /// Low 8 bits (STATE_MASK): the behaviour's display state (0 = roaming / default; the search
    /// behaviour uses STATE_COOPERATIVE, STATE_DECLARED), recorded per tick and used to colour
    /// trajectories. Higher bits: behaviour-declared event flags.
    pub events: u32,
    pub vel: [f64; 2],
    /// Messages sent this tick and their destinations (BROADCAST or a robot id).
    pub n_sent: u32,
    /// Radio outcome of the messages due at this tick, as the receiver's transport saw them.
    pub radio_delivered: u32,
    pub radio_dropped_loss: u32,
    pub radio_malformed: u32,
    pub sent_to: [u32; MAX_SENT],
}

impl Action {
    pub fn idle(tick: u64, robot: u32) -> Action {
        Action {
            tick,
            robot,
            events: 0,
            vel: [0.0, 0.0],
            n_sent: 0,
            radio_delivered: 0,
            radio_dropped_loss: 0,
            radio_malformed: 0,
            sent_to: [0; MAX_SENT],
        }
    }
}

pub const STATE_MASK: u32 = 0xff;
pub const STATE_ROAMING: u32 = 0;
pub const STATE_COOPERATIVE: u32 = 1;
pub const STATE_DECLARED: u32 = 2;

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
    pub targets: u32,
    pub found: u32,
    pub offered: u64,
    pub delivered: u64,
    pub dropped_range: u64,
    pub dropped_loss: u64,
    pub rejected_actions: u64,
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
        assert_eq!(std::mem::align_of::<Sense>(), 8);
        assert_eq!(
            std::mem::size_of::<Sense>(),
            72 + 4 * MAX_NEIGHBOURS + 16 * MAX_OBSTACLE_POINTS + 16 * MAX_SIGNALS
        );
        assert_eq!(std::mem::size_of::<Action>(), 48 + 4 * MAX_SENT);
    }

    #[test]
    fn zeroed_sense_has_empty_lists() {
        let s = Sense::zeroed();
        assert!(s.neighbours().is_empty());
        assert!(s.obstacle_points().is_empty());
        assert!(s.signals().is_empty());
    }

    #[test]
    fn list_accessors_clamp_corrupt_counts() {
        let mut s = Sense::zeroed();
        s.n_neighbours = u32::MAX;
        assert_eq!(s.neighbours().len(), MAX_NEIGHBOURS);
    }
}
