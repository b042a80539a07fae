//! Ground truth and the per-tick step: senses out, actions in.

use crate::body::{bounding_box, BodySummary, Statics};
use crate::kinematics::{self, Limit};
use crate::medium::{Medium, MediumParams, TickAir};
use crate::metrics::Coverage;
use crate::mission::{self, Mission, MissionError};
use crate::placement::{place_robots, PlacementError};
use crate::sensing::{
    fill_nearby, fill_obstacles, grid_cell, static_points, PointGrid, SenseScratch,
};
use swarm::frames::{
    Action, RadioHeader, Sense, WorldStatus, MAX_SENT, RUN_RUNNING, RUN_STOPPING, STATE_MASK,
};
use swarm::geometry::{polygon_hit, v2, Vec2};
use swarm::mailbox::Air;
use swarm::radio::RadioCounters;
use swarm::recording::{Event, RejectReason, TickExtra, TickRecord};
use swarm::scenario::{Kinematics, Scenario};

/// Why a world could not be built from a (validated) scenario.
#[derive(Debug, thiserror::Error)]
pub enum WorldError {
    #[error(transparent)]
    Placement(#[from] PlacementError),
    #[error(transparent)]
    Mission(#[from] MissionError),
}

/// How far short of an obstacle or wall a blocked move stops.
const BLOCK_BACKOFF: f64 = 0.5;
/// Relative tolerance on the speed limit (behaviours clamp with floating-point rounding).
const SPEED_TOLERANCE: f64 = 1e-9;
/// Bisections that place a blocked disc robot at the last clear point of its step (the
/// error is the step's length / 2^40).
const DISC_BISECTIONS: u32 = 40;

/// A robot that died, for the summary.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Fault {
    pub robot: u32,
    /// The tick the fault happened at: the scheduled tick of a chaos kill, or the tick the
    /// orchestrator had last seen when it reaped the process.
    pub tick: u64,
    /// First tick at which the world treated the robot as dead (stopped waiting for it).
    pub detected_tick: u64,
    pub cause: String,
    /// Wall-clock milliseconds from the orchestrator's reaping the process to the world's
    /// handling it (None for faults the world decided itself).
    pub detection_ms: Option<f64>,
    /// Tick from which a restarted agent drove the robot again (policy "restart").
    pub restarted_tick: Option<u64>,
}

pub struct World {
    pub sc: Scenario,
    pub n: usize,
    /// Agents with a body: 0..bodies; the rest (`run.stations`) are stations, which only
    /// talk on the radio (no motion, not sensed as robots, not counted by the mission).
    pub bodies: usize,
    pub tick: u64,
    pub poses: Vec<[f64; 3]>,
    pub vel: Vec<[f64; 2]>,
    pub alive: Vec<bool>,
    grid: PointGrid,
    /// Each obstacle's bounding box (min x, min y, max x, max y), for `clip_move`.
    obstacle_boxes: Vec<[f64; 4]>,
    dead_points: Vec<[f64; 2]>,
    scratch: SenseScratch,
    /// The radio: decides every (message, receiver) pair and holds the delay.
    medium: Medium,
    /// The messages due at the current tick (taken from the medium by `begin_tick`).
    due: Option<TickAir>,
    /// Scratch of `apply`, kept for their allocations: messages per sender, whose radio is
    /// taken this tick, and the messages handed to the medium.
    sent_per_robot: Vec<usize>,
    radio_taken: Vec<bool>,
    outgoing: Vec<(RadioHeader, usize)>,
    /// The air is lent ([`World::lend_air`]): the medium copies no payload, and the caller
    /// writes each air from the buffer its messages were sent in.
    lend_air: bool,
    pub radio: RadioCounters,
    /// The same counters in payload bytes (each pair counts its message's length).
    pub radio_bytes: RadioCounters,
    pub faults: Vec<Fault>,
    pub rejected: [u64; 6],
    pub blocked_moves: u64,
    pub distance_travelled: f64,
    pending_events: Vec<Event>,
    stopping: bool,
    /// Trajectories for the picture, sampled every `traj_every` ticks.
    /// Sampled (x, y, display state) of each robot.
    pub trajectories: Vec<Vec<[f64; 3]>>,
    /// Each robot's display state from its last action.
    pub states: Vec<u8>,
    pub coverage: Coverage,
    pub start: Vec<[f64; 2]>,
    traj_every: u64,
    /// The run's SIGKILL schedule (swarm::chaos) and the next entry due.
    kills: Vec<[u64; 2]>,
    next_kill: usize,
    /// The paper's mission (entities, completion, metrics, its picture layer).
    pub mission: Box<dyn Mission>,
    /// Each agent's own [speed, turn rate] limits per tick, when the mission gives them
    /// (`Mission::robot_limits`); None: `robot.v_max` and the kinematics' `w_max` for all.
    limits: Option<Vec<[f64; 2]>>,
    /// Walls and obstacles as disc bodies meet them (robot.radius > 0).
    statics: Statics,
    /// The run's worst body figures (robot.radius > 0).
    pub body: Option<BodySummary>,
    /// Real-time mode (`runtime.realtime_hz` > 0): a live robot without an action this tick
    /// missed its deadline and keeps its last command; in lock-step it stands still.
    realtime: bool,
    /// Each robot's last command the world applied (None: stand still; after a rejected
    /// action, a death or a revive).
    last_cmd: Vec<Option<[f64; 2]>>,
    /// Real-time mode: the deadlines each robot missed.
    pub misses: Vec<u64>,
    /// Real-time mode: actions read after their tick's deadline (their messages went out at
    /// the tick they were read, their commands were superseded).
    pub late_actions: u64,
    /// Real-time mode: (live robot, tick) pairs, the denominator of the miss rate.
    pub robot_ticks: u64,
}

fn reason_index(r: RejectReason) -> usize {
    match r {
        RejectReason::NotFinite => 0,
        RejectReason::TooFast => 1,
        RejectReason::WrongRobot => 2,
        RejectReason::WrongTick => 3,
        RejectReason::BadRadioReport => 4,
        RejectReason::TurnTooFast => 5,
    }
}

pub const REJECT_NAMES: [&str; 6] = [
    "not_finite",
    "too_fast",
    "wrong_robot",
    "wrong_tick",
    "bad_radio_report",
    "turn_too_fast",
];

/// Margin of a step's bounding box when `clip_move` culls obstacles by box (units).
const MOVE_BOX_MARGIN: f64 = 1e-3;
/// Shortest step whose obstacles are culled by box: segment_hit counts an edge parallel to the
/// step within ~1e-9 / len of its line as touched, 1e-6 units at this length.
const MIN_CULLED_MOVE: f64 = 1e-3;

/// Smallest t in [0, 1] at which the segment p -> p + v enters the disc `d` (a point robot's
/// step), None if it does not.
fn disc_hit(p: Vec2, v: Vec2, d: &swarm::scenario::DiscObstacle) -> Option<f64> {
    let f = p - Vec2::new(d.centre[0], d.centre[1]);
    let (a, b, c) = (v.dot(&v), 2.0 * f.dot(&v), f.dot(&f) - d.radius * d.radius);
    if c <= 0.0 {
        return Some(0.0);
    }
    let disc = b * b - 4.0 * a * c;
    if a == 0.0 || disc < 0.0 {
        return None;
    }
    let t = (-b - disc.sqrt()) / (2.0 * a);
    (0.0..=1.0).contains(&t).then_some(t)
}

impl World {
    pub fn new(sc: &Scenario) -> Result<World, WorldError> {
        let mut rng = swarm::streams::rng(
            sc.run.seed,
            swarm::streams::WORLD,
            swarm::streams::PLACEMENT,
        );
        let mission = mission::create(sc)?;
        let (start, headings): (Vec<[f64; 2]>, Vec<f64>) = match mission.start_poses(sc) {
            Some(poses) => poses.iter().map(|p| ([p[0], p[1]], p[2])).unzip(),
            None => {
                let start = place_robots(sc, &mut rng)?;
                let zeros = vec![0.0; start.len()];
                (start, zeros)
            }
        };
        let n = start.len();
        let grid = PointGrid::new(
            static_points(sc),
            sc.arena.width,
            sc.arena.height,
            grid_cell(sc),
        );
        let traj_every = (sc.run.max_ticks / 2000).max(1);
        let limits = mission.robot_limits(sc);
        Ok(World {
            sc: sc.clone(),
            n,
            bodies: sc.bodies() as usize,
            tick: 0,
            poses: start
                .iter()
                .zip(&headings)
                .map(|(p, h)| [p[0], p[1], *h])
                .collect(),
            vel: vec![[0.0; 2]; n],
            alive: vec![true; n],
            grid,
            obstacle_boxes: sc
                .arena
                .obstacles
                .iter()
                .map(|o| bounding_box(&o.points))
                .collect(),
            dead_points: Vec::new(),
            scratch: SenseScratch::default(),
            medium: Medium::new(sc, MediumParams::from_scenario(sc)),
            due: None,
            sent_per_robot: Vec::new(),
            radio_taken: Vec::new(),
            lend_air: false,
            outgoing: Vec::new(),
            radio: RadioCounters::default(),
            radio_bytes: RadioCounters::default(),
            faults: Vec::new(),
            rejected: [0; 6],
            blocked_moves: 0,
            distance_travelled: 0.0,
            pending_events: Vec::new(),
            stopping: false,
            coverage: {
                let mut c = Coverage::new(sc.arena.width, sc.arena.height);
                start.iter().for_each(|p| c.visit(*p));
                c
            },
            trajectories: start.iter().map(|p| vec![[p[0], p[1], 0.0]]).collect(),
            states: vec![0; n],
            start,
            traj_every,
            kills: swarm::chaos::schedule(sc),
            next_kill: 0,
            mission,
            limits,
            statics: Statics::new(sc),
            body: (sc.robot.radius > 0.0).then(|| BodySummary::new(sc.robot.radius)),
            realtime: sc.runtime.is_realtime(),
            last_cmd: vec![None; n],
            misses: vec![0; n],
            late_actions: 0,
            robot_ticks: 0,
        })
    }

    pub fn alive_count(&self) -> u32 {
        self.alive.iter().filter(|a| **a).count() as u32
    }

    pub fn live_robots(&self) -> impl Iterator<Item = u32> + '_ {
        self.alive
            .iter()
            .enumerate()
            .filter(|(_, a)| **a)
            .map(|(i, _)| i as u32)
    }

    /// From now on the medium lends each tick's air (`Medium::transmit_lent`): its payloads
    /// stay in the `sent` buffer handed to [`World::apply`], and the caller writes the air due
    /// at the next tick ([`World::air`]) from that same, unchanged buffer
    /// (`swarm::air::write_air_from`): the payloads are copied once between the tick's buffer
    /// and the air sample instead of twice (DESIGN-NOTES, "The air written from the sender's
    /// buffer", step 1). With `radio.delay_ticks` > 0 the medium still copies (the air
    /// outlives the buffer). Decisions, counters and recordings are the same either way. The
    /// in-process executor does not lend: its mailbox reads the payloads from the air.
    pub fn lend_air(&mut self) {
        self.lend_air = true;
    }

    /// The run will end after this tick; Sense frames say so.
    pub fn set_stopping(&mut self) {
        self.stopping = true;
    }

    /// Writes robot i's Sense frame for the current tick into `out` (in place: every field the
    /// agent reads is written, lists up to their counts).
    pub fn sense(&mut self, i: usize, out: &mut Sense) {
        self.sense_mission(i, out);
        let mut scratch = std::mem::take(&mut self.scratch);
        self.sense_geometry(i, &mut scratch, out);
        self.scratch = scratch;
    }

    /// The part of [`World::sense`] that may draw from the mission's random streams (sensor
    /// noise, drawn in robot order): the robot's own state and the mission's entities. Must be
    /// called for the live robots in id order, before their [`World::sense_geometry`].
    pub fn sense_mission(&mut self, i: usize, out: &mut Sense) {
        let p = self.poses[i];
        out.tick = self.tick;
        out.robot = i as u32;
        out.run_state = if self.stopping {
            RUN_STOPPING
        } else {
            RUN_RUNNING
        };
        out.pos = [p[0], p[1]];
        out.heading = p[2];
        out.vel = self.vel[i];
        out.alive_robots = self.alive_count();
        out.n_entities = 0;
        self.mission.sense(i as u32, [p[0], p[1]], out);
    }

    /// The rest of [`World::sense`]: the obstacle points and the robots nearby. Reads only
    /// this tick's ground truth, so it may run for several robots at once (the in-process
    /// executor's threads).
    pub fn sense_geometry(&self, i: usize, scratch: &mut SenseScratch, out: &mut Sense) {
        let p = self.poses[i];
        fill_obstacles(
            &self.grid,
            &self.dead_points,
            [p[0], p[1]],
            self.sc.robot.sensing_radius,
            scratch,
            out,
        );
        out.n_nearby = 0;
        if self.sc.robot.neighbour_sensing_radius > 0.0 && i < self.bodies {
            fill_nearby(
                i,
                &self.poses,
                &self.vel,
                &self.alive,
                self.sc.robot.neighbour_sensing_radius,
                scratch,
                out,
            );
            if self.bodies < self.n {
                // Stations have no body: a robot's own sensors do not see them.
                let keep: Vec<_> = out
                    .nearby()
                    .iter()
                    .copied()
                    .filter(|q| (q.robot as usize) < self.bodies)
                    .collect();
                out.nearby[..keep.len()].copy_from_slice(&keep);
                out.n_nearby = keep.len() as u32;
            }
        }
    }

    /// Marks a robot dead from the current tick on: it stands still as an obstacle.
    /// `happened` is when the fault occurred, if known to be earlier than now.
    pub fn mark_dead(
        &mut self,
        robot: u32,
        cause: &str,
        happened: Option<u64>,
        detection_ms: Option<f64>,
    ) {
        let i = robot as usize;
        if i >= self.n || !self.alive[i] {
            return;
        }
        self.alive[i] = false;
        self.vel[i] = [0.0; 2];
        self.last_cmd[i] = None;
        if i < self.bodies {
            self.dead_points.push([self.poses[i][0], self.poses[i][1]]);
        }
        self.faults.push(Fault {
            robot,
            tick: happened.unwrap_or(self.tick).min(self.tick),
            detected_tick: self.tick,
            cause: cause.to_string(),
            detection_ms,
            restarted_tick: None,
        });
        self.pending_events.push(Event::RobotDied {
            robot,
            cause: cause.to_string(),
        });
    }

    /// Applies the scheduled kills of the current tick (faults.kill_at): the robot is dead from
    /// exactly this tick, whenever its process receives the SIGKILL.
    /// Takes the radio messages due at this tick from the medium ([`World::air`]).
    pub fn begin_tick(&mut self) {
        let k = self.tick;
        if let Some(spent) = self.due.take() {
            self.medium.recycle(spent);
        }
        self.due = self.medium.due(k);
        while let Some(&[t, r]) = self.kills.get(self.next_kill) {
            if t > k {
                break;
            }
            self.next_kill += 1;
            if t == k {
                self.mark_dead(r as u32, "scheduled SIGKILL (chaos)", Some(k), None);
            }
        }
    }

    /// The radio messages due at the current tick (sent at tick - 1 - delay_ticks), if any
    /// were: every agent's inbox is its list in it.
    pub fn air(&self) -> Option<&TickAir> {
        self.due.as_ref()
    }

    /// Whether `robot` has a scheduled kill at the current tick that `begin_tick` has not
    /// applied yet (its SIGKILL can be reaped before the world starts that tick).
    pub fn kill_scheduled_now(&self, robot: u32) -> bool {
        self.kills[self.next_kill..]
            .iter()
            .take_while(|e| e[0] <= self.tick)
            .any(|e| e[0] == self.tick && e[1] == robot as u64)
    }

    /// A restarted agent drives the robot again from the current tick. Returns false (and
    /// changes nothing) if the robot is not dead: the world has not yet learnt of the death
    /// that the restart answers, so the caller must try again on a later tick.
    pub fn revive(&mut self, robot: u32) -> bool {
        let i = robot as usize;
        if i >= self.n || self.alive[i] {
            return false;
        }
        self.alive[i] = true;
        self.last_cmd[i] = None;
        let p = [self.poses[i][0], self.poses[i][1]];
        if let Some(j) = self.dead_points.iter().position(|q| *q == p) {
            self.dead_points.remove(j);
        }
        if let Some(f) = self
            .faults
            .iter_mut()
            .rev()
            .find(|f| f.robot == robot && f.restarted_tick.is_none())
        {
            f.restarted_tick = Some(self.tick);
        }
        self.pending_events.push(Event::RobotRestarted { robot });
        true
    }

    pub fn restarts(&self) -> u64 {
        self.faults
            .iter()
            .filter(|f| f.restarted_tick.is_some())
            .count() as u64
    }

    fn validate(&self, i: usize, a: &Action) -> Result<(), RejectReason> {
        if a.robot as usize != i {
            return Err(RejectReason::WrongRobot);
        }
        if a.tick != self.tick {
            return Err(RejectReason::WrongTick);
        }
        if !a.cmd[0].is_finite() || !a.cmd[1].is_finite() {
            return Err(RejectReason::NotFinite);
        }
        let (k, v_max) = self.limits_of(i);
        match kinematics::within_limits(&k, a.cmd, v_max, SPEED_TOLERANCE) {
            Limit::Within => Ok(()),
            Limit::TooFast => Err(RejectReason::TooFast),
            Limit::TurnTooFast => Err(RejectReason::TurnTooFast),
        }
    }

    /// Robot i's kinematics with its own turn limit, and its own speed limit (per tick): the
    /// mission's (`Mission::robot_limits`), else the scenario's `robot` section.
    fn limits_of(&self, i: usize) -> (Kinematics, f64) {
        let k = self.sc.robot.kinematics;
        match self.limits.as_ref().and_then(|l| l.get(i)) {
            // Never above the scenario's own limits.
            Some(&[v, w]) => {
                let v = v.min(self.sc.robot.v_max);
                match k {
                    Kinematics::Unicycle { w_max } => (
                        Kinematics::Unicycle {
                            w_max: w.min(w_max),
                        },
                        v,
                    ),
                    Kinematics::Holonomic => (k, v),
                }
            }
            None => (k, self.sc.robot.v_max),
        }
    }

    /// Where a step from p along v ends: stops short of obstacles and walls (the whole segment
    /// is checked, not only its end point; for disc robots, the disc along it).
    fn clip_move(&self, p: Vec2, v: Vec2) -> (Vec2, bool) {
        let len = v.norm();
        if len == 0.0 {
            return (p, false);
        }
        if self.sc.robot.radius > 0.0 {
            return self.clip_disc_move(p, v);
        }
        let t = self.first_hit(p, v, len >= MIN_CULLED_MOVE);
        match t {
            None => (p + v, false),
            Some(t) => {
                let s = ((t * len - BLOCK_BACKOFF) / len).max(0.0);
                (p + v * s, true)
            }
        }
    }

    /// [`World::clip_move`] for a disc of `robot.radius`: the step is walked in sub-steps of at
    /// most half a radius; at the first sub-step whose end the disc cannot stand on, the last
    /// clear fraction comes from a bisection. A disc that starts overlapping (a scenario may
    /// start it so) may move wherever its clearance does not shrink.
    fn clip_disc_move(&self, p: Vec2, v: Vec2) -> (Vec2, bool) {
        let r = self.sc.robot.radius;
        let at = |s: f64| p + v * s;
        let clear_at = |s: f64| {
            let q = at(s);
            self.statics.clearance([q.x, q.y])
        };
        let start = clear_at(0.0);
        let ok = |s: f64| {
            let c = clear_at(s);
            c >= r || (start < r && c >= start)
        };
        let steps = ((v.norm() / (0.5 * r)).ceil() as usize).clamp(1, 1000);
        let mut last = 0.0;
        for k in 1..=steps {
            let s = k as f64 / steps as f64;
            if !ok(s) {
                let (mut lo, mut hi) = (last, s);
                for _ in 0..DISC_BISECTIONS {
                    let mid = 0.5 * (lo + hi);
                    if ok(mid) {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                return (at(lo), true);
            }
            last = s;
        }
        (at(1.0), false)
    }

    /// Smallest t in [0, 1] at which the step p -> p + v meets a wall or an obstacle. With
    /// `cull`, an obstacle whose bounding box the step's box (widened by MOVE_BOX_MARGIN, far
    /// more than segment_hit's collinearity tolerance of ~1e-9 / len) misses is not tested:
    /// it cannot be hit. Tiny steps are not culled, as that tolerance grows with 1 / len.
    fn first_hit(&self, p: Vec2, v: Vec2, cull: bool) -> Option<f64> {
        let (w, h) = (self.sc.arena.width, self.sc.arena.height);
        let walls = [[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]];
        let mut t = polygon_hit(p, v, &walls);
        let (q, m) = (p + v, MOVE_BOX_MARGIN);
        let step = [
            p.x.min(q.x) - m,
            p.y.min(q.y) - m,
            p.x.max(q.x) + m,
            p.y.max(q.y) + m,
        ];
        for (o, b) in self.sc.arena.obstacles.iter().zip(&self.obstacle_boxes) {
            let apart = b[0] > step[2] || b[2] < step[0] || b[1] > step[3] || b[3] < step[1];
            if cull && apart {
                continue;
            }
            if let Some(x) = polygon_hit(p, v, &o.points) {
                t = Some(t.map_or(x, |y: f64| y.min(x)));
            }
        }
        for d in &self.sc.arena.discs {
            if let Some(x) = disc_hit(p, v, d) {
                t = Some(t.map_or(x, |y: f64| y.min(x)));
            }
        }
        t
    }

    /// Applies the actions of the current tick (index = robot; None = no action arrived) and
    /// the radio messages the robots sent with them (`sent`, any order; a robot's are taken
    /// only with a valid action of its own), and advances to the next tick. Returns the
    /// tick's record.
    pub fn apply(&mut self, actions: &[Option<Action>], sent: &Air) -> TickRecord {
        self.apply_with_late(actions, &[], sent)
    }

    /// [`World::apply`] in real-time mode: `late[i]` is robot i's action for an earlier tick
    /// that arrived after that tick's deadline and was read at this one (index = robot; a
    /// shorter slice: none). Its command is superseded (the robot kept its last command at
    /// its own tick) and its malformed report is void (its list of that tick was counted
    /// with the miss), but its messages, which are in `sent` beside this tick's, go out now,
    /// sent at this tick. A live robot with no action of this tick missed its deadline: it
    /// keeps its last command and the miss is counted (`misses`, an `Event::DeadlineMissed`).
    pub fn apply_with_late(
        &mut self,
        actions: &[Option<Action>],
        late: &[Option<Action>],
        sent: &Air,
    ) -> TickRecord {
        let k = self.tick;
        let mut events = std::mem::take(&mut self.pending_events);
        let mut radio = RadioCounters::default();
        let mut bytes = RadioCounters::default();
        // The messages due now: each receiver's list, delivered or malformed as it reports, or
        // lost with it when it is dead or sent no action.
        let radio_ok = |i: usize, a: &Option<Action>| matches!(a, Some(a) if a.robot as usize == i && a.tick == k);
        let deliveries = self.sc.runtime.record_deliveries.then(|| {
            crate::heard::deliveries(self.due.as_ref(), self.n, |i| {
                let a = actions.get(i).copied().flatten();
                (self.alive[i] && radio_ok(i, &a)).then(|| a.map_or(0, |a| a.radio_malformed))
            })
        });
        if let Some(due) = self.due.take() {
            for i in 0..due.robots().min(self.n) {
                let listed = due.deliveries(i as u32).len() as u64;
                if listed == 0 {
                    continue;
                }
                let listed_bytes = due.bytes_to(i as u32);
                let a = actions.get(i).copied().flatten();
                if self.alive[i] && radio_ok(i, &a) {
                    let bad = (a.expect("checked").radio_malformed as u64).min(listed);
                    radio.malformed += bad;
                    radio.delivered += listed - bad;
                    // The receiver reports how many it could not decode, not which: all of
                    // its bytes count as delivered unless all its messages were malformed.
                    if bad == listed {
                        bytes.malformed += listed_bytes;
                    } else {
                        bytes.delivered += listed_bytes;
                    }
                } else {
                    radio.receiver_dead += listed;
                    bytes.receiver_dead += listed_bytes;
                }
            }
            self.medium.recycle(due);
        }
        // The messages sent now: a live robot's, with its own valid action, as many as it
        // says it sent (at most radio.max_messages_per_tick). The world's ground truth fills
        // in sender, tick and position.
        let counts = &mut self.sent_per_robot;
        counts.clear();
        counts.resize(self.n, 0);
        for (h, _) in sent.entries() {
            if let Some(c) = counts.get_mut(h.sender as usize) {
                *c += 1;
            }
        }
        let cap = MAX_SENT.min(self.sc.radio.max_messages_per_tick as usize);
        self.radio_taken.clear();
        self.radio_taken.resize(self.n, false);
        for i in 0..self.n {
            if !self.alive[i] {
                continue;
            }
            // This tick's valid action, and (real-time mode) a late one of an earlier tick:
            // each within the cap, together as many as the robot's messages in `sent`.
            let a = actions
                .get(i)
                .copied()
                .flatten()
                .filter(|a| radio_ok(i, &Some(*a)));
            let l = late
                .get(i)
                .copied()
                .flatten()
                .filter(|l| l.robot as usize == i && l.tick < k);
            if a.is_none() && l.is_none() {
                continue;
            }
            let reports = [a, l];
            let each = reports.iter().flatten().map(|r| r.n_sent as usize);
            if each.clone().any(|n_sent| n_sent > cap)
                || each.sum::<usize>() != self.sent_per_robot[i]
            {
                self.reject(&mut events, i, RejectReason::BadRadioReport);
                continue;
            }
            self.radio_taken[i] = true;
        }
        self.late_actions += late.iter().flatten().count() as u64;
        self.robot_ticks += self.alive.iter().filter(|a| **a).count() as u64;
        self.outgoing.clear();
        for &(h, at) in sent.entries() {
            let i = h.sender as usize;
            if i < self.n && self.radio_taken[i] {
                let mut h = h;
                h.tick = k;
                h.sender_pos = [self.poses[i][0], self.poses[i][1]];
                self.outgoing.push((h, at));
            }
        }
        let c = if self.lend_air {
            self.medium
                .transmit_lent(k, &self.outgoing, sent.bytes(), &self.poses, &self.alive)
        } else {
            self.medium
                .transmit(k, &self.outgoing, sent.bytes(), &self.poses, &self.alive)
        };
        for (out, t) in [(&mut radio, &c.pairs), (&mut bytes, &c.bytes)] {
            out.offered = t.offered;
            out.dropped_range = t.dropped_range;
            out.dropped_occluded = t.dropped_occluded;
            out.dropped_bandwidth = t.dropped_bandwidth;
            out.dropped_loss = t.dropped_loss;
        }
        radio.in_flight = self.medium.in_flight();
        bytes.in_flight = self.medium.in_flight_bytes();
        // Motion.
        for i in 0..self.n {
            if !self.alive[i] {
                continue;
            }
            let Some(a) = actions.get(i).copied().flatten() else {
                if !self.realtime {
                    self.vel[i] = [0.0; 2];
                    continue;
                }
                // Real-time mode: the deadline passed without this tick's action.
                self.misses[i] += 1;
                events.push(Event::DeadlineMissed { robot: i as u32 });
                match self.last_cmd[i] {
                    Some(cmd) if i < self.bodies => self.step_robot(i, cmd, &mut events),
                    _ => self.vel[i] = [0.0; 2],
                }
                continue;
            };
            if i >= self.bodies {
                // A station does not move: its command is ignored, its state and its report
                // are taken.
                if a.robot as usize == i && a.tick == k {
                    self.states[i] = (a.events & STATE_MASK) as u8;
                    self.mission.observe(i as u32, a.report);
                }
                continue;
            }
            if let Err(r) = self.validate(i, &a) {
                self.reject(&mut events, i, r);
                self.vel[i] = [0.0; 2];
                self.last_cmd[i] = None;
                continue;
            }
            self.states[i] = (a.events & STATE_MASK) as u8;
            self.mission.observe(i as u32, a.report);
            if a.events & !STATE_MASK != 0 {
                events.push(Event::Declared {
                    robot: i as u32,
                    flags: a.events & !STATE_MASK,
                });
            }
            self.last_cmd[i] = Some(a.cmd);
            self.step_robot(i, a.cmd, &mut events);
        }
        self.mission
            .update(k, &self.poses, &self.alive, &mut events);
        let extra = self.body.as_mut().map(|summary| {
            let f = crate::body::figures(
                &self.statics,
                &self.poses[..self.bodies],
                self.sc.robot.radius,
            );
            summary.add(&f);
            TickExtra { body: Some(f) }
        });
        self.radio.add(&radio);
        self.radio_bytes.add(&bytes);
        if (k + 1).is_multiple_of(self.traj_every) {
            for i in 0..self.n {
                self.trajectories[i].push([
                    self.poses[i][0],
                    self.poses[i][1],
                    self.states[i] as f64,
                ]);
            }
        }
        self.tick += 1;
        TickRecord {
            tick: k,
            poses: self.poses.clone(),
            alive: self.alive.iter().map(|&a| a as u8).collect(),
            states: self.states.clone(),
            events,
            radio,
            radio_bytes: bytes,
            extra,
            layer: None,
            deliveries,
        }
    }

    /// Moves robot i one tick by command `cmd` (validated), stopping short of obstacles.
    fn step_robot(&mut self, i: usize, cmd: [f64; 2], events: &mut Vec<Event>) {
        let p = Vec2::new(self.poses[i][0], self.poses[i][1]);
        let (step, turned) = kinematics::intended(&self.sc.robot.kinematics, self.poses[i], cmd);
        let (q, blocked) = self.clip_move(p, v2(step));
        if blocked {
            self.blocked_moves += 1;
            events.push(Event::MoveBlocked { robot: i as u32 });
        }
        let moved = q - p;
        self.distance_travelled += moved.norm();
        let heading = match turned {
            Some(h) => h,
            None if moved.norm() > 0.0 => moved.y.atan2(moved.x),
            None => self.poses[i][2],
        };
        self.poses[i] = [q.x, q.y, heading];
        self.coverage.visit([q.x, q.y]);
        self.vel[i] = [moved.x, moved.y];
    }

    /// Deadlines missed so far, all robots (real-time mode).
    pub fn total_misses(&self) -> u64 {
        self.misses.iter().sum()
    }

    /// The recording version this run writes: 6, with the radio's byte counters (and a
    /// TickExtra and TickLayer a tick, empty when the run has no body and no layer); 7 when it
    /// records who heard whom (`runtime.record_deliveries`, opt-in).
    pub fn recording_version(&self) -> u32 {
        if self.sc.runtime.record_deliveries {
            swarm::recording::RECORDING_VERSION_DELIVERIES
        } else {
            swarm::recording::RECORDING_VERSION_BYTES
        }
    }

    fn reject(&mut self, events: &mut Vec<Event>, i: usize, r: RejectReason) {
        self.rejected[reason_index(r)] += 1;
        events.push(Event::ActionRejected {
            robot: i as u32,
            reason: r,
        });
    }

    /// Closes the radio books at the end of the run: what is still in flight (the air
    /// taken for a tick that never ran included).
    pub fn finish_radio(&mut self) {
        self.radio.in_flight = self.medium.in_flight() + self.due.as_ref().map_or(0, |a| a.pairs());
        self.radio_bytes.in_flight = self.medium.in_flight_bytes()
            + self
                .due
                .as_ref()
                .map_or(0, |a| a.bytes_to.iter().sum::<u64>());
    }

    /// Why the run ends after this tick, if it does: the mission is complete, or every robot
    /// is dead with no restart on its way. The one place both executors ask.
    pub fn end_reason(&self) -> Option<&'static str> {
        if self.mission.complete() {
            Some(self.mission.end_reason())
        } else if !self.alive[..self.bodies].iter().any(|a| *a) && !self.restart_due() {
            Some("all robots dead")
        } else {
            None
        }
    }

    /// Under `faults.on_fault = "restart"`, whether a dead robot has a restart left: the
    /// orchestrator restarts a robot's k-th death while k <= max_restarts, so its new agent
    /// is on its way (issue 37 item 9: killing every robot ended the run).
    fn restart_due(&self) -> bool {
        let f = &self.sc.faults;
        f.on_fault == swarm::scenario::FaultPolicy::Restart
            && (0..self.bodies).any(|i| {
                !self.alive[i]
                    && self.faults.iter().filter(|x| x.robot as usize == i).count()
                        <= f.max_restarts as usize
            })
    }

    pub fn status(&self, finished: bool) -> WorldStatus {
        let alive = self.alive_count();
        WorldStatus {
            tick: self.tick,
            max_ticks: self.sc.run.max_ticks,
            alive,
            dead: self.n as u32 - alive,
            finished: finished as u32,
            restarted: self.restarts() as u32,
            progress_total: self.mission.progress().1,
            progress_done: self.mission.progress().0,
            offered: self.radio.offered,
            delivered: self.radio.delivered,
            dropped_range: self.radio.dropped_range,
            dropped_loss: self.radio.dropped_loss,
            dropped_other: self.radio.dropped_occluded
                + self.radio.dropped_bandwidth
                + self.radio.receiver_dead
                + self.radio.malformed,
            rejected_actions: self.rejected.iter().sum(),
            deadline_misses: self.total_misses(),
        }
    }
}

#[cfg(test)]
#[path = "realtime_tests.rs"]
mod realtime_tests;

#[cfg(test)]
mod tests {
    use super::*;

    fn world() -> World {
        let mut sc = Scenario::roam();
        sc.run.robots = 5;
        World::new(&sc).unwrap()
    }

    #[test]
    fn bad_actions_are_rejected_counted_and_the_world_carries_on() {
        let mut w = world();
        let mut acts: Vec<Option<Action>> = (0..5).map(|i| Some(Action::idle(0, i))).collect();
        acts[0].as_mut().unwrap().cmd = [f64::NAN, 0.0];
        acts[1].as_mut().unwrap().cmd = [f64::INFINITY, 0.0];
        acts[2].as_mut().unwrap().cmd = [1e9, 0.0];
        acts[3].as_mut().unwrap().robot = 77;
        acts[4].as_mut().unwrap().n_sent = 1000;
        let before = w.poses.clone();
        let rec = w.apply(&acts, &Air::default());
        assert_eq!(w.rejected, [2, 1, 1, 0, 1, 0]);
        assert_eq!(rec.events.len(), 5);
        assert_eq!(&w.poses[..4], &before[..4]);
        assert!(w.poses.iter().all(|p| p.iter().all(|x| x.is_finite())));
        assert_eq!(w.tick, 1);
    }

    #[test]
    fn moves_never_cross_an_obstacle_or_leave_the_arena() {
        let mut w = world();
        // Robot 0 just left of the convex block's left edge, pushed right into it.
        w.poses[0] = [285.0, 260.0, 0.0];
        // Robot 1 at the wall, pushed out.
        w.poses[1] = [3.0, 50.0, 0.0];
        let mut acts: Vec<Option<Action>> = (0..5).map(|i| Some(Action::idle(0, i))).collect();
        acts[0].as_mut().unwrap().cmd = [10.0, 0.0];
        acts[1].as_mut().unwrap().cmd = [-10.0, 0.0];
        w.apply(&acts, &Air::default());
        // The block's left edge crosses y = 260 at x = 294.545...: the robot stops 0.5 short.
        assert!(
            (w.poses[0][0] - (300.0 - 600.0 / 110.0 - 0.5)).abs() < 1e-9,
            "{:?}",
            w.poses[0]
        );
        let block = &w.sc.arena.obstacles[0].points;
        assert!(!swarm::geometry::point_in_polygon(
            v2([w.poses[0][0], w.poses[0][1]]),
            block
        ));
        assert!(w.poses[1][0] >= 0.0, "{:?}", w.poses[1]);
        assert_eq!(w.blocked_moves, 2);
    }

    #[test]
    fn a_point_robot_step_stops_where_it_enters_a_disc() {
        let d = swarm::scenario::DiscObstacle {
            name: "d".into(),
            centre: [5.0, 0.0],
            radius: 1.0,
        };
        // Along +x from 0 by 10: enters the circle at x = 4, t = 0.4.
        let t = disc_hit(Vec2::new(0.0, 0.0), Vec2::new(10.0, 0.0), &d).unwrap();
        assert!((t - 0.4).abs() < 1e-12, "{t}");
        // Passing 2 above the centre: no hit; too short to reach it: none.
        assert_eq!(
            disc_hit(Vec2::new(0.0, 2.0), Vec2::new(10.0, 0.0), &d),
            None
        );
        assert_eq!(disc_hit(Vec2::new(0.0, 0.0), Vec2::new(3.0, 0.0), &d), None);
    }

    #[test]
    fn dead_robots_stand_still_and_are_sensed_as_obstacles() {
        let mut w = world();
        w.poses[1] = [50.0, 50.0, 0.0];
        w.poses[0] = [60.0, 50.0, 0.0];
        w.mark_dead(1, "test", None, None);
        let acts: Vec<Option<Action>> = (0..5)
            .map(|i| {
                let mut a = Action::idle(0, i);
                a.cmd = [1.0, 0.0];
                Some(a)
            })
            .collect();
        w.apply(&acts, &Air::default());
        assert_eq!(&w.poses[1][..2], &[50.0, 50.0]);
        let mut s = Sense::zeroed();
        w.sense(0, &mut s);
        assert!(s.obstacle_points().contains(&[50.0, 50.0]));
        assert_eq!(w.faults.len(), 1);
    }

    #[test]
    fn the_counts_of_a_broadcast_add_up_from_send_to_due_tick() {
        use swarm::wire::RadioTx;
        let mut w = world();
        for i in 0..5 {
            w.poses[i] = [10.0 + i as f64 * 100.0, 10.0, 0.0];
        }
        let mut acts: Vec<Option<Action>> = (0..5).map(|i| Some(Action::idle(0, i))).collect();
        let a0 = acts[0].as_mut().unwrap();
        a0.n_sent = 1;
        a0.sent_to[0] = swarm::frames::BROADCAST;
        let mut air = Air::default();
        let h = RadioHeader {
            sender: 0,
            len: 3,
            ..Default::default()
        };
        air.transmit(&h, &mut |b| b.copy_from_slice(&[1, 2, 3]));
        w.begin_tick();
        let rec = w.apply(&acts, &air);
        // Robot 0 at x=10 reaches x=110, 210, 310 (<= 300 away) but not x=410.
        assert_eq!(rec.radio.offered, 4);
        assert_eq!(rec.radio.dropped_range, 1);
        assert_eq!(rec.radio.in_flight, 3);
        // Next tick: robot 3 died, robot 2 could not decode, robot 1 got it.
        w.mark_dead(3, "test", None, None);
        w.begin_tick();
        let due = w.air().expect("due at tick 1");
        assert_eq!(
            (1..5).map(|r| due.deliveries(r).len()).collect::<Vec<_>>(),
            vec![1, 1, 1, 0]
        );
        let mut acts: Vec<Option<Action>> = (0..5).map(|i| Some(Action::idle(1, i))).collect();
        acts[2].as_mut().unwrap().radio_malformed = 1;
        acts[3] = None;
        let rec = w.apply(&acts, &Air::default());
        let r = rec.radio;
        assert_eq!(
            (r.delivered, r.malformed, r.receiver_dead, r.in_flight),
            (1, 1, 1, 0)
        );
        assert_eq!(w.radio.offered, w.radio.accounted());
    }

    #[test]
    fn a_robot_whose_messages_disagree_with_its_action_is_refused_its_radio() {
        use swarm::wire::RadioTx;
        let mut w = world();
        let mut air = Air::default();
        let h = RadioHeader {
            sender: 1,
            len: 1,
            ..Default::default()
        };
        air.transmit(&h, &mut |b| b[0] = 9);
        // Robot 1 says it sent nothing, but a message of its is there.
        let acts: Vec<Option<Action>> = (0..5).map(|i| Some(Action::idle(0, i))).collect();
        w.begin_tick();
        let rec = w.apply(&acts, &air);
        assert_eq!(rec.radio.offered, 0);
        assert_eq!(w.rejected[reason_index(RejectReason::BadRadioReport)], 1);
    }

    #[test]
    fn culling_obstacles_by_box_finds_the_same_first_hits() {
        use rand::{Rng, SeedableRng};
        let w = World::new(&Scenario::default()).expect("world");
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(8);
        let mut hits = 0;
        // Random steps, many starting on or next to obstacle edges and vertices, of every
        // length from 1e-3 (the shortest culled) to 40, and along the edges themselves.
        let corners: Vec<[f64; 2]> =
            w.sc.arena
                .obstacles
                .iter()
                .flat_map(|o| o.points.iter().copied())
                .collect();
        for k in 0..20000 {
            let p = if k % 2 == 0 {
                let c = corners[rng.gen_range(0..corners.len())];
                v2([
                    c[0] + rng.gen_range(-3.0..3.0),
                    c[1] + rng.gen_range(-3.0..3.0),
                ])
            } else {
                v2([rng.gen_range(0.0..1000.0), rng.gen_range(0.0..1000.0)])
            };
            let len = 10f64.powf(rng.gen_range(-3.0..1.6));
            let a = if k % 5 == 0 {
                0.0
            } else {
                rng.gen_range(0.0..std::f64::consts::TAU)
            };
            let v = v2([len * a.cos(), len * a.sin()]);
            let culled = w.first_hit(p, v, true);
            assert_eq!(
                culled.map(f64::to_bits),
                w.first_hit(p, v, false).map(f64::to_bits)
            );
            hits += culled.is_some() as usize;
        }
        assert!(hits > 500, "{hits}");
    }

    #[test]
    fn a_unicycle_turning_at_its_limit_traces_the_arc_of_eqs_2_8_to_2_10() {
        let mut sc = Scenario::roam();
        sc.run.robots = 1;
        sc.arena.obstacles.clear();
        let w_max = 0.2;
        sc.robot.kinematics = swarm::scenario::Kinematics::Unicycle { w_max };
        let mut w = World::new(&sc).unwrap();
        let (x0, y0, phi0) = (500.0, 500.0, 0.3);
        w.poses[0] = [x0, y0, phi0];
        let v = sc.robot.v_max;
        // Eqs. (2.8)-(2.10) with constant (v, w): every step is a chord of length v turning by
        // w, so the positions are vertices of a regular polygon on the circle of radius
        // R = v / (2 sin(w / 2)), centred on the perpendicular bisector of the first chord,
        // (v / 2) / tan(w / 2) to its left.
        let big_r = v / (2.0 * (w_max / 2.0).sin());
        let d = v / 2.0 / (w_max / 2.0).tan();
        let centre = [
            x0 + v / 2.0 * (phi0).cos() + d * (phi0 + std::f64::consts::FRAC_PI_2).cos(),
            y0 + v / 2.0 * (phi0).sin() + d * (phi0 + std::f64::consts::FRAC_PI_2).sin(),
        ];
        for k in 0..40 {
            let mut act = Action::idle(w.tick, 0);
            act.cmd = [v, w_max];
            w.apply(&[Some(act)], &Air::default());
            let p = w.poses[0];
            let r = ((p[0] - centre[0]).powi(2) + (p[1] - centre[1]).powi(2)).sqrt();
            assert!((r - big_r).abs() < 1e-9, "tick {k}: {r} vs {big_r}");
            let heading = crate::kinematics::wrap(phi0 + (k + 1) as f64 * w_max);
            assert!((p[2] - heading).abs() < 1e-9, "tick {k}: heading {}", p[2]);
        }
        // Over the limit: rejected, the robot stands still.
        let before = w.poses[0];
        let mut act = Action::idle(w.tick, 0);
        act.cmd = [v, w_max * 1.01];
        w.apply(&[Some(act)], &Air::default());
        assert_eq!(w.poses[0], before);
        assert_eq!(w.rejected[reason_index(RejectReason::TurnTooFast)], 1);
    }

    #[test]
    fn disc_robots_stop_at_their_radius_and_their_overlaps_are_counted() {
        let mut sc = Scenario::roam();
        sc.run.robots = 3;
        sc.robot.radius = 2.0;
        let mut w = World::new(&sc).unwrap();
        assert_eq!(
            w.recording_version(),
            swarm::recording::RECORDING_VERSION_BYTES
        );
        // Robot 0 heads right into the convex block's left edge (x = 294.545 at y = 260):
        // its centre stops 2 (the radius) short, not 0.5 as a point robot does.
        w.poses[0] = [285.0, 260.0, 0.0];
        // Robots 1 and 2 overlap (centres 3 apart, radius 2: clearance -1).
        w.poses[1] = [50.0, 50.0, 0.0];
        w.poses[2] = [53.0, 50.0, 0.0];
        let mut acts: Vec<Option<Action>> = (0..3).map(|i| Some(Action::idle(0, i))).collect();
        acts[0].as_mut().unwrap().cmd = [10.0, 0.0];
        let rec = w.apply(&acts, &Air::default());
        let edge_x = 300.0 - 600.0 / 110.0;
        let gap = edge_x - w.poses[0][0];
        // The distance to the slanted edge is the horizontal gap times cos of its slope.
        let clearance = w.statics.clearance([w.poses[0][0], w.poses[0][1]]);
        assert!(
            (2.0 - 1e-9..2.0 + 1e-6).contains(&clearance),
            "{clearance} (gap {gap})"
        );
        assert_eq!(w.blocked_moves, 1);
        let f = rec
            .extra
            .and_then(|e| e.body)
            .expect("body figures every tick");
        assert!((f.min_robot_clearance + 1.0).abs() < 1e-12, "{f:?}");
        assert_eq!(f.overlapping_pairs, 1);
        assert_eq!(f.obstacle_overlaps, 0);
        let b = w.body.expect("summary figures");
        assert_eq!((b.max_overlapping_pairs, b.ticks_with_overlap), (1, 1));
        // A point-robot world writes no figures (its recording's TickExtra is empty).
        let w = World::new(&Scenario::roam()).unwrap();
        assert!(w.body.is_none());
    }

    #[test]
    fn robots_sense_nearby_robots_with_positions_and_velocities_only_within_range() {
        let mut sc = Scenario::roam();
        sc.run.robots = 4;
        sc.robot.neighbour_sensing_radius = 20.0;
        let mut w = World::new(&sc).unwrap();
        w.poses[0] = [100.0, 100.0, 0.0];
        w.poses[1] = [110.0, 100.0, 0.0];
        w.poses[2] = [100.0, 125.0, 0.0];
        w.poses[3] = [90.0, 95.0, 0.0];
        w.vel[1] = [1.0, 2.0];
        let mut s = Sense::zeroed();
        w.sense(0, &mut s);
        let ids: Vec<u32> = s.nearby().iter().map(|n| n.robot).collect();
        assert_eq!(ids, vec![1, 3]);
        assert_eq!(s.nearby()[0].pos, [110.0, 100.0]);
        assert_eq!(s.nearby()[0].vel, [1.0, 2.0]);
        w.mark_dead(3, "test", None, None);
        w.sense(0, &mut s);
        assert_eq!(s.nearby().len(), 1);
        // Off by default: robots learn of each other over the radio only.
        let mut w = World::new(&Scenario::roam()).unwrap();
        w.sense(0, &mut s);
        assert!(s.nearby().is_empty());
    }

    #[test]
    fn a_station_has_no_body_but_is_on_the_radio() {
        let sc = Scenario::parse(
            include_str!("../../configs/hunt-example-3a.toml"),
            "hunt-example-3a.toml",
        )
        .unwrap();
        let mut w = World::new(&sc).unwrap();
        assert_eq!((w.n, w.bodies), (16, 15));
        // The robots start at Table 3.2's positions, the auctioneer at its own.
        assert_eq!(&w.poses[0][..2], &[1.54, 6.88]);
        assert_eq!(&w.poses[15][..2], &[5.0, 5.0]);
        // A robot next to the station: the station is not in its sensors (it is on the radio
        // like any agent: the medium's tests cover that).
        w.poses[0] = [5.1, 5.0, 0.0];
        let mut s = Sense::zeroed();
        w.sense(0, &mut s);
        assert!(s.nearby().iter().all(|q| q.robot != 15));
        // Its command is ignored (even one over the limits), its state is recorded.
        let mut acts: Vec<Option<Action>> = (0..16).map(|i| Some(Action::idle(0, i))).collect();
        acts[15].as_mut().unwrap().cmd = [1e9, 7.0];
        acts[15].as_mut().unwrap().events = 255;
        let rec = w.apply(&acts, &Air::default());
        assert_eq!(&w.poses[15][..2], &[5.0, 5.0]);
        assert_eq!(rec.states[15], 255);
        assert_eq!(w.rejected.iter().sum::<u64>(), 0);
        // Dead, it leaves no obstacle point; the run ends only when every body is dead.
        w.mark_dead(15, "test", None, None);
        assert!(w.dead_points.is_empty());
        assert_eq!(w.end_reason(), None);
    }
}
