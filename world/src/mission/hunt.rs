//! The hunting thesis's mission (003, chapters 2-3; docs/hunting.md sections 1.4, 1.8): evaders
//! that appear (at the start, or mid-run: T5 of Example 3-A), stay silent until a pursuer comes
//! within their sensing radius, then flee by the escape strategy of eq. (2.17) with the
//! encirclement slowdown (`hunt_escape`), and are captured when their coalition stands at its
//! hunting points around them and encloses them. A captured evader stops for good. The run is
//! complete when every evader is captured.
//!
//! The world knows the coalitions only from what the robots report (Action `report`, see
//! `swarm::sections::hunt`): a robot names its task and its hunting point. It judges capture
//! from ground truth: for evader j (at its position of tick k, the one the robots sensed),
//! - at least L_j live robots report task j;
//! - each stands within `capture_tolerance` of the point it reports, and that point lies on
//!   the circle r_s around the evader within the same tolerance;
//! - together they carry E_j (2.6);
//! - they enclose it: the largest bearing gap between them, seen from the evader, is below pi.
//!
//! The auctioneer (the station, the last agent) reports the awards it has made, one task a tick
//! in turn: `report` = [task, reward paid z_j, auction rounds so far, 0]; the mission keeps the
//! last reward of each task for its metrics (Table 3.3).

use super::hunt_escape::{escape, ArenaBox, EscapeParams};
use super::{DisplayState, LegendEntry, Mark, Mission, MissionEntry, MissionError, RunFacts};
use serde::Serialize;
use std::f64::consts::PI;
use swarm::frames::{Entity, Sense, ENTITY_HAS_POS};
use swarm::geometry::Vec2;
use swarm::recording::Event;
use swarm::scenario::{Check, ConfigError, Kinematics, Scenario};
use swarm::sections::hunt::{
    EvaderSpec, HuntParams, Resources, ENTITY_EVADER, EVADER_CAPTURED, MAX_EVADERS_SENSED,
    STATE_AUCTIONEER,
};

pub const ENTRY: MissionEntry = MissionEntry {
    name: "hunt",
    progress_label: "evaders captured",
    implied_by: &["hunt"],
    sections: &["hunt"],
    validate,
    new,
};

/// Relative slack on the speed and turn limits the scenario's robot section must allow.
const LIMIT_SLACK: f64 = 1e-9;
/// Ticks between two samples of an evader's path (for run.svg).
const PATH_EVERY: u64 = 5;
/// Samples of an evader's path the viewer's layer shows (`Mission::live_layer`): its last
/// 5 minutes at 0.05 min a tick. [chosen] 20: run.svg keeps the whole path.
const LIVE_TRAIL_SAMPLES: usize = 20;

/// Checks the `[hunt]` section against the rest of the scenario.
fn validate(sc: &Scenario, c: &Check) -> Result<(), ConfigError> {
    let h = &sc.hunt();
    h.validate(c)?;
    if h.robots.is_empty() || h.evaders.is_empty() {
        // What asked for the hunt: the mission named, or the behaviour that implies it.
        let (key, value) = match &sc.run.mission {
            Some(m) => ("run.mission", m.as_str()),
            None => ("run.behaviour", sc.run.behaviour.as_str()),
        };
        return Err(c.err(
            key,
            format!(
                "= {value:?} runs the hunt mission, which needs [[hunt.robots]] and \
                 [[hunt.evaders]] rows (configs/hunt-auction.toml); the scenario has {} and {}",
                h.robots.len(),
                h.evaders.len()
            ),
        ));
    }
    // The auction runs an auctioneer station; a decentralised behaviour (cbca) runs none.
    let want = h.robots.len() as u64 + u64::from(sc.run.behaviour == "hunt");
    let stations = u32::from(sc.run.behaviour == "hunt");
    if sc.run.robots as u64 != want || sc.run.stations != stations {
        return Err(c.err(
            "run.robots",
            format!(
                "= {} with run.stations = {}: a hunt runs one agent per [[hunt.robots]] row \
                 ({}) plus, for the auction (behaviour hunt), the auctioneer: run.robots = \
                 {want} and run.stations = {stations}",
                sc.run.robots,
                sc.run.stations,
                h.robots.len()
            ),
        ));
    }
    let inside = |p: [f64; 2]| {
        (0.0..=sc.arena.width).contains(&p[0]) && (0.0..=sc.arena.height).contains(&p[1])
    };
    for (k, r) in h.robots.iter().enumerate() {
        if !inside(r.position) {
            return Err(c.err(
                &format!("hunt.robots[{k}].position"),
                format!("= {:?} lies outside the arena", r.position),
            ));
        }
    }
    for (k, e) in h.evaders.iter().enumerate() {
        if !inside(e.position) {
            return Err(c.err(
                &format!("hunt.evaders[{k}].position"),
                format!("= {:?} lies outside the arena", e.position),
            ));
        }
    }
    if !inside(h.auctioneer.position) {
        return Err(c.err(
            "hunt.auctioneer.position",
            format!("= {:?} lies outside the arena", h.auctioneer.position),
        ));
    }
    let v = h.max_speed_per_tick();
    if sc.robot.v_max < v * (1.0 - LIMIT_SLACK) {
        return Err(c.err(
            "robot.v_max",
            format!(
                "= {} is below the fastest hunt robot's speed per tick ({v} km = speed x \
                 hunt.params.minutes_per_tick)",
                sc.robot.v_max
            ),
        ));
    }
    match sc.robot.kinematics {
        Kinematics::Unicycle { w_max } if w_max >= h.max_turn_per_tick() * (1.0 - LIMIT_SLACK) => {
        }
        k => {
            return Err(c.err(
                "robot.kinematics",
                format!(
                    "= {k:?}: the hunt needs model = \"unicycle\" (eqs. 2.8-2.10) with w_max >= \
                     {} rad per tick (the fastest turn_rate x hunt.params.minutes_per_tick)",
                    h.max_turn_per_tick()
                ),
            ))
        }
    }
    Ok(())
}

fn new(sc: &Scenario) -> Result<Box<dyn Mission>, MissionError> {
    Ok(Box::new(HuntMission::new(sc)))
}

/// One evader's state.
#[derive(Debug, Clone)]
pub struct Evader {
    pub spec: EvaderSpec,
    pub pos: Vec2,
    pub appear_tick: u64,
    pub present: bool,
    /// Tick of the first move (a pursuer came within its sensing radius).
    pub pursued_at: Option<u64>,
    /// Tick of capture and the coalition (world robot indices) that made it.
    pub captured: Option<(u64, Vec<u32>)>,
    /// The speed it ran at in the last tick, km/min.
    pub speed_now: f64,
    /// Sampled positions (every `PATH_EVERY` ticks while it moves), for run.svg.
    pub path: Vec<[f64; 2]>,
    pub distance_run: f64,
}

/// A change of a coalition, as the robots' reports show it.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct CoalitionChange {
    pub tick: u64,
    pub task: u32,
    /// Thesis robot ids (hunt.robots[k].id), ascending.
    pub members: Vec<u32>,
}

/// The hunt's measures (summary.json `mission.hunt`).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct HuntMetrics {
    pub evaders: u32,
    pub captured: u32,
    /// captured / evaders.
    pub capture_rate: f64,
    /// Per evader.
    pub per_evader: Vec<EvaderMetrics>,
    /// Mean of the capture times, minutes (None: nothing captured).
    pub mean_capture_minutes: Option<f64>,
    /// Minutes from the start to the last capture (None unless every evader was captured).
    pub all_captured_minutes: Option<f64>,
    /// Rounds the auctioneer reported (all its auctions together).
    pub auction_rounds: u32,
    /// The auctioneer's cost C (3.13) and the winners' total utility Y (3.14) over every
    /// auction it finished, as it last reported them (None: never reported).
    pub auction_cost: Option<f64>,
    pub auction_utility: Option<f64>,
    /// Every change of a coalition (robots reporting a task), in tick order.
    pub coalition_changes: Vec<CoalitionChange>,
}

#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct EvaderMetrics {
    pub id: u32,
    pub appear_tick: u64,
    pub captured_tick: Option<u64>,
    /// Minutes from its appearance to its capture.
    pub capture_minutes: Option<f64>,
    /// The coalition that captured it (thesis robot ids).
    pub captured_by: Vec<u32>,
    /// The reward the auctioneer last reported paying for it (None: never awarded).
    pub reward_paid: Option<f64>,
    pub reward_cap: f64,
    pub distance_run_km: f64,
}

pub struct HuntMission {
    p: HuntParams,
    esc: EscapeParams,
    arena: ArenaBox,
    bodies: usize,
    station: u32,
    robot_ids: Vec<u32>,
    robot_resources: Vec<Resources>,
    pub evaders: Vec<Evader>,
    /// Each robot's report of this tick (NaN-free zeros when none).
    reports: Vec<[f64; 4]>,
    /// Each task's members as last reported (world indices).
    members: Vec<Vec<u32>>,
    pub changes: Vec<CoalitionChange>,
    /// The auctioneer's last reported reward per task (index as `evaders`).
    rewards: Vec<Option<f64>>,
    rounds: u32,
    /// The auctioneer's last totals row: (C, Y) over its finished auctions.
    auction_totals: Option<(f64, f64)>,
    /// Live robots' last positions (for the picture's encirclements).
    last_poses: Vec<[f64; 3]>,
    dt: f64,
}

impl HuntMission {
    pub fn new(sc: &Scenario) -> HuntMission {
        let h = &sc.hunt();
        let p = h.params.clone();
        HuntMission {
            esc: EscapeParams {
                sensing_radius: p.evader_sensing_radius,
                wall_margin: p.evader_wall_margin,
                encirclement_slowdown: p.encirclement_slowdown,
            },
            arena: ArenaBox {
                width: sc.arena.width,
                height: sc.arena.height,
            },
            bodies: sc.bodies() as usize,
            station: sc.bodies(),
            robot_ids: h.robots.iter().map(|r| r.id).collect(),
            robot_resources: h.robots.iter().map(|r| r.resources).collect(),
            evaders: h
                .evaders
                .iter()
                .map(|e| Evader {
                    spec: e.clone(),
                    pos: Vec2::new(e.position[0], e.position[1]),
                    appear_tick: e.appear_tick(&p),
                    present: e.appear_tick(&p) == 0,
                    pursued_at: None,
                    captured: None,
                    speed_now: 0.0,
                    path: vec![e.position],
                    distance_run: 0.0,
                })
                .collect(),
            reports: vec![[0.0; 4]; sc.bodies() as usize],
            members: vec![Vec::new(); h.evaders.len()],
            changes: Vec::new(),
            rewards: vec![None; h.evaders.len()],
            rounds: 0,
            auction_totals: None,
            last_poses: Vec::new(),
            dt: p.minutes_per_tick,
            p,
        }
    }

    /// The hunt mission of `world`, if it runs one.
    pub fn of(world: &crate::World) -> Option<&HuntMission> {
        world.mission.as_any().downcast_ref::<HuntMission>()
    }

    fn index_of(&self, task: u32) -> Option<usize> {
        self.evaders.iter().position(|e| e.spec.id == task)
    }

    /// The capture rule (module doc) for evader `j` at its current position.
    fn captured_now(&self, j: usize, poses: &[[f64; 3]], alive: &[bool]) -> Option<Vec<u32>> {
        let e = &self.evaders[j];
        let tol = self.p.capture_tolerance;
        let members: Vec<usize> = (0..self.bodies.min(poses.len()))
            .filter(|&i| alive[i] && self.reports[i][0] == e.spec.id as f64)
            .collect();
        if members.len() < e.spec.required_robots {
            return None;
        }
        let mut bearings = Vec::with_capacity(members.len());
        let mut carried = [0.0; 6];
        for &i in &members {
            let x = Vec2::new(poses[i][0], poses[i][1]);
            let r = self.reports[i];
            let point = Vec2::new(r[1], r[2]);
            if !(point.x.is_finite() && point.y.is_finite())
                || (x - point).norm() > tol
                || ((point - e.pos).norm() - self.p.r_s).abs() > tol
            {
                return None;
            }
            let d = x - e.pos;
            bearings.push(d.y.atan2(d.x));
            for (c, have) in carried.iter_mut().zip(&self.robot_resources[i]) {
                *c += have;
            }
        }
        if carried.iter().zip(&e.spec.resources).any(|(c, w)| c < w) {
            return None;
        }
        // A wall that cuts the r_s circle encloses the target like a pursuer (the hunting
        // points then lie on the circle's arc inside the arena: `hunting_points_inside_arena`).
        if self.p.hunting_points_inside_arena {
            bearings.extend(super::hunt_escape::wall_bearings(&e.pos, &self.arena, self.p.r_s));
        }
        let (_, gap) = super::hunt_escape::largest_gap(&mut bearings);
        (gap < PI).then(|| members.iter().map(|&i| i as u32).collect())
    }

    /// The layer's marks (run.svg, the viewer), each evader's path cut to its last `trail`
    /// samples.
    fn marks(&self, trail: usize) -> Vec<Mark> {
        let mut marks = Vec::new();
        for (j, e) in self.evaders.iter().enumerate() {
            let col = colour_of(e.spec.id);
            let mut path = e.path[e.path.len().saturating_sub(trail)..].to_vec();
            path.push([e.pos.x, e.pos.y]);
            marks.push(Mark::Path {
                points: path,
                colour: col,
            });
            marks.push(Mark::Circle {
                at: [e.pos.x, e.pos.y],
                radius: self.p.effective_range(e.spec.required_robots),
                colour: col,
            });
            marks.push(Mark::Circle {
                at: [e.pos.x, e.pos.y],
                radius: self.p.r_s,
                colour: BLACK,
            });
            // The hunting points the members last reported.
            for &i in &self.members[j] {
                let r = self.reports[i as usize];
                if r[1].is_finite() && r[2].is_finite() && r[0] >= 1.0 {
                    marks.push(Mark::Ring {
                        at: [r[1], r[2]],
                        px: 3,
                        colour: col,
                        width: 1,
                    });
                }
            }
            marks.push(if e.captured.is_some() {
                captured_mark([e.pos.x, e.pos.y])
            } else {
                Mark::Ring {
                    at: [e.pos.x, e.pos.y],
                    px: 5,
                    colour: BLACK,
                    width: 2,
                }
            });
        }
        // Robots as triangles along their heading, by coalition colour (Figs. 3.3-3.5).
        for (i, q) in self.last_poses.iter().enumerate() {
            let task = self.reports[i][0];
            let state = if task >= 1.0 { task as u32 } else { 0 };
            marks.push(Mark::Triangle {
                at: [q[0], q[1]],
                heading: q[2],
                px: 9,
                fill: colour_of(state),
            });
        }
        marks
    }

    fn track_coalitions(&mut self, tick: u64, alive: &[bool]) {
        for j in 0..self.evaders.len() {
            let id = self.evaders[j].spec.id as f64;
            let now: Vec<u32> = (0..self.bodies)
                .filter(|&i| alive.get(i).copied().unwrap_or(false) && self.reports[i][0] == id)
                .map(|i| i as u32)
                .collect();
            if now != self.members[j] {
                let mut ids: Vec<u32> = now.iter().map(|&i| self.robot_ids[i as usize]).collect();
                ids.sort_unstable();
                self.changes.push(CoalitionChange {
                    tick,
                    task: self.evaders[j].spec.id,
                    members: ids,
                });
                self.members[j] = now;
            }
        }
    }

    pub fn hunt_metrics(&self) -> HuntMetrics {
        let per_evader: Vec<EvaderMetrics> = self
            .evaders
            .iter()
            .zip(&self.rewards)
            .map(|(e, z)| EvaderMetrics {
                id: e.spec.id,
                appear_tick: e.appear_tick,
                captured_tick: e.captured.as_ref().map(|c| c.0),
                capture_minutes: e
                    .captured
                    .as_ref()
                    .map(|c| (c.0 + 1 - e.appear_tick) as f64 * self.dt),
                captured_by: e.captured.as_ref().map_or(Vec::new(), |c| {
                    let mut v: Vec<u32> =
                        c.1.iter().map(|&i| self.robot_ids[i as usize]).collect();
                    v.sort_unstable();
                    v
                }),
                reward_paid: *z,
                reward_cap: e.spec.reward_cap,
                distance_run_km: e.distance_run,
            })
            .collect();
        let times: Vec<f64> = per_evader.iter().filter_map(|e| e.capture_minutes).collect();
        let captured = times.len() as u32;
        let n = self.evaders.len() as u32;
        HuntMetrics {
            evaders: n,
            captured,
            capture_rate: captured as f64 / n.max(1) as f64,
            mean_capture_minutes: (!times.is_empty())
                .then(|| times.iter().sum::<f64>() / times.len() as f64),
            all_captured_minutes: (captured == n).then(|| {
                per_evader
                    .iter()
                    .filter_map(|e| e.captured_tick)
                    .max()
                    .map_or(0.0, |t| (t + 1) as f64 * self.dt)
            }),
            auction_rounds: self.rounds,
            auction_cost: self.auction_totals.map(|t| t.0),
            auction_utility: self.auction_totals.map(|t| t.1),
            coalition_changes: self.changes.clone(),
            per_evader,
        }
    }
}

/// Coalition colours (display state = task id; Figs. 3.3-3.5 colour robots by coalition).
const STATES: &[DisplayState] = &[
    DisplayState {
        state: 0,
        name: "free",
        colour: [150, 150, 150],
    },
    DisplayState {
        state: 1,
        name: "T1",
        colour: [220, 40, 40],
    },
    DisplayState {
        state: 2,
        name: "T2",
        colour: [40, 120, 220],
    },
    DisplayState {
        state: 3,
        name: "T3",
        colour: [30, 160, 60],
    },
    DisplayState {
        state: 4,
        name: "T4",
        colour: [230, 140, 0],
    },
    DisplayState {
        state: 5,
        name: "T5",
        colour: [150, 60, 200],
    },
    DisplayState {
        state: 6,
        name: "T6",
        colour: [0, 170, 170],
    },
    DisplayState {
        state: 7,
        name: "T7",
        colour: [200, 60, 140],
    },
    DisplayState {
        state: 8,
        name: "T8",
        colour: [120, 100, 40],
    },
    DisplayState {
        state: STATE_AUCTIONEER as u8,
        name: "auctioneer",
        // Navy, not black: black marks a free evader.
        colour: [0, 0, 110],
    },
];

fn colour_of(state: u32) -> [u8; 3] {
    STATES
        .iter()
        .find(|d| d.state as u32 == state)
        .map_or(STATES[0].colour, |d| d.colour)
}

const BLACK: [u8; 3] = [0, 0, 0];
/// A captured evader's fill: not black, which marks a free one (its ring) and the auctioneer.
const CAPTURED: [u8; 3] = [255, 200, 0];

fn captured_mark(at: [f64; 2]) -> Mark {
    Mark::Disc {
        at,
        px: 5,
        fill: CAPTURED,
        outline: Some(BLACK),
    }
}

impl Mission for HuntMission {
    fn name(&self) -> &'static str {
        "hunt"
    }
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    fn start_poses(&self, sc: &Scenario) -> Option<Vec<[f64; 3]>> {
        let mut v: Vec<[f64; 3]> = sc
            .hunt()
            .robots
            .iter()
            .map(|r| [r.position[0], r.position[1], r.heading])
            .collect();
        if sc.run.stations > 0 {
            let a = sc.hunt().auctioneer.position;
            v.push([a[0], a[1], 0.0]);
        }
        Some(v)
    }
    /// Each robot's own speed and turn rate (km/min, rad/min in `[[hunt.robots]]`) times
    /// `minutes_per_tick`; the station, which never moves, gets none (0, 0).
    fn robot_limits(&self, sc: &Scenario) -> Option<Vec<[f64; 2]>> {
        let dt = sc.hunt().params.minutes_per_tick;
        let mut v: Vec<[f64; 2]> = sc
            .hunt()
            .robots
            .iter()
            .map(|r| [r.speed * dt, r.turn_rate * dt])
            .collect();
        v.resize(sc.run.robots as usize, [0.0, 0.0]);
        Some(v)
    }
    fn sense(&mut self, robot: u32, pos: [f64; 2], out: &mut Sense) {
        if robot as usize >= self.bodies {
            out.n_entities = 0; // the auctioneer senses nothing: it knows what it hears
            return;
        }
        let p = Vec2::new(pos[0], pos[1]);
        let mut n = 0;
        for e in self.evaders.iter().filter(|e| e.present) {
            if n >= MAX_EVADERS_SENSED || (e.pos - p).norm() > self.p.detection_radius {
                continue;
            }
            out.entities[n] = Entity {
                id: e.spec.id,
                kind: ENTITY_EVADER,
                flags: ENTITY_HAS_POS | if e.captured.is_some() { EVADER_CAPTURED } else { 0 },
                reserved: 0,
                pos: [e.pos.x, e.pos.y],
                value: e.speed_now,
            };
            n += 1;
        }
        out.n_entities = n as u32;
    }
    fn observe(&mut self, robot: u32, report: [f64; 4]) {
        if robot == self.station {
            if let Some(j) = self.index_of(report[0] as u32).filter(|_| report[0] >= 1.0) {
                if report[1].is_finite() {
                    self.rewards[j] = Some(report[1]);
                }
            } else if report[0] == 0.0 && report[1].is_finite() && report[3].is_finite() {
                // The totals row: [0, C, rounds, Y].
                self.auction_totals = Some((report[1], report[3]));
            }
            if report[2].is_finite() && report[2] >= 0.0 {
                self.rounds = self.rounds.max(report[2] as u32);
            }
        } else if let Some(r) = self.reports.get_mut(robot as usize) {
            *r = report;
        }
    }
    fn update(&mut self, tick: u64, poses: &[[f64; 3]], alive: &[bool], events: &mut Vec<Event>) {
        let poses = &poses[..self.bodies.min(poses.len())];
        self.track_coalitions(tick, alive);
        // Capture, against the evaders' positions of this tick (those the robots sensed).
        for j in 0..self.evaders.len() {
            if !self.evaders[j].present || self.evaders[j].captured.is_some() {
                continue;
            }
            if let Some(members) = self.captured_now(j, poses, alive) {
                events.push(Event::EntityDone {
                    entity: self.evaders[j].spec.id,
                    robot: members[0],
                });
                self.evaders[j].speed_now = 0.0;
                self.evaders[j].captured = Some((tick, members));
            }
        }
        // The others flee (2.17) from every live robot they sense.
        let pursuers: Vec<Vec2> = poses
            .iter()
            .zip(alive)
            .filter(|(_, a)| **a)
            .map(|(q, _)| Vec2::new(q[0], q[1]))
            .collect();
        for e in self.evaders.iter_mut() {
            if !e.present || e.captured.is_some() {
                e.speed_now = 0.0;
                continue;
            }
            match escape(&e.pos, &pursuers, &self.arena, &self.esc) {
                None => e.speed_now = 0.0,
                Some(esc) => {
                    e.pursued_at.get_or_insert(tick);
                    let v = e.spec.speed * esc.speed_factor;
                    let step = v * self.dt;
                    let next = e.pos + step * Vec2::new(esc.heading.cos(), esc.heading.sin());
                    let next = Vec2::new(
                        next.x.clamp(0.0, self.arena.width),
                        next.y.clamp(0.0, self.arena.height),
                    );
                    e.distance_run += (next - e.pos).norm();
                    e.pos = next;
                    e.speed_now = v;
                    if tick.is_multiple_of(PATH_EVERY) {
                        e.path.push([next.x, next.y]);
                    }
                }
            }
        }
        // Evaders that appear at the next tick are sensed from then on.
        for e in self.evaders.iter_mut() {
            if !e.present && e.appear_tick <= tick + 1 {
                e.present = true;
            }
        }
        self.last_poses = poses.to_vec();
    }
    fn progress(&self) -> (u32, u32) {
        (
            self.evaders.iter().filter(|e| e.captured.is_some()).count() as u32,
            self.evaders.len() as u32,
        )
    }
    fn complete(&self) -> bool {
        self.evaders.iter().all(|e| e.captured.is_some())
    }
    fn end_reason(&self) -> &'static str {
        "all evaders captured"
    }
    fn metrics(&self, _facts: &RunFacts) -> Option<serde_json::Value> {
        serde_json::to_value(self.hunt_metrics()).ok()
    }
    fn display_states(&self) -> &'static [DisplayState] {
        STATES
    }
    fn layer(&self) -> Vec<Mark> {
        self.marks(usize::MAX)
    }
    /// The viewer's layer: run.svg's marks with each evader's path cut to its last
    /// `LIVE_TRAIL_SAMPLES` samples, so a tick's record stays the same size all run long
    /// (with the whole path, recording.bin grew with the square of the run's length).
    fn live_layer(&self) -> Vec<Mark> {
        self.marks(LIVE_TRAIL_SAMPLES)
    }
    fn legend(&self) -> Vec<LegendEntry> {
        vec![
            LegendEntry {
                mark: captured_mark([0.0; 2]),
                label: "evader captured",
            },
            LegendEntry {
                mark: Mark::Ring {
                    at: [0.0; 2],
                    px: 5,
                    colour: BLACK,
                    width: 2,
                },
                label: "evader free (circles: r_e, r_s)",
            },
            LegendEntry {
                mark: Mark::Triangle {
                    at: [0.0; 2],
                    heading: 0.0,
                    px: 9,
                    fill: STATES[1].colour,
                },
                label: "robot (colour: its task)",
            },
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn example() -> Scenario {
        Scenario::parse(
            include_str!("../../../configs/hunt-example-3a.toml"),
            "hunt-example-3a.toml",
        )
        .expect("parses")
    }

    fn check(sc: &Scenario) -> Result<(), ConfigError> {
        validate(
            sc,
            &Check {
                key_source: &|_| "t.toml".to_string(),
            },
        )
    }

    #[test]
    fn example_3a_is_valid_and_a_wrong_agent_count_is_refused() {
        let sc = example();
        check(&sc).unwrap();
        let mut bad = sc.clone();
        bad.run.robots = 15;
        assert_eq!(check(&bad).unwrap_err().key, "run.robots");
        let mut bad = sc.clone();
        bad.robot.kinematics = Kinematics::Holonomic;
        assert_eq!(check(&bad).unwrap_err().key, "robot.kinematics");
        let mut bad = sc;
        bad.robot.v_max = 0.01;
        assert_eq!(check(&bad).unwrap_err().key, "robot.v_max");
    }

    #[test]
    fn the_world_holds_each_robot_to_its_own_speed_and_turn_rate() {
        use swarm::frames::Action;
        use swarm::mailbox::Air;
        let mut sc = example();
        // R2 turns at 2 rad/min = 0.1 rad a tick, below the scenario's w_max of 0.3.
        sc.hunt_mut().robots[1].turn_rate = 2.0;
        let mut w = crate::World::new(&sc).unwrap();
        let slot = |name: &str| crate::world::REJECT_NAMES.iter().position(|n| *n == name);
        let (too_fast, turn) = (slot("too_fast").unwrap(), slot("turn_too_fast").unwrap());
        // R1 (agent 0) runs at 0.8 km/min = 0.04 km a tick; robot.v_max is 0.045 (R2's 0.9).
        let step = |w: &mut crate::World, robot: u32, cmd: [f64; 2]| {
            let mut acts: Vec<Option<Action>> = (0..sc.run.robots)
                .map(|i| Some(Action::idle(w.tick, i)))
                .collect();
            acts[robot as usize].as_mut().unwrap().cmd = cmd;
            let before = w.poses[robot as usize];
            w.apply(&acts, &Air::default());
            let after = w.poses[robot as usize];
            ((after[0] - before[0]).hypot(after[1] - before[1]), after[2] - before[2])
        };
        let (d, _) = step(&mut w, 0, [0.04, 0.0]);
        assert!((d - 0.04).abs() < 1e-12, "at its own limit it moves: {d}");
        assert_eq!(w.rejected[too_fast], 0);
        // 0.042 is under robot.v_max but over R1's own 0.04: rejected, it stands still.
        let (d, _) = step(&mut w, 0, [0.042, 0.0]);
        assert_eq!((d, w.rejected[too_fast]), (0.0, 1));
        // R2 may run at 0.045 a tick (0.9 km/min), and turn 0.1 rad a tick but not 0.15.
        let (d, dphi) = step(&mut w, 1, [0.045, 0.1]);
        assert!((d - 0.045).abs() < 1e-12 && (dphi - 0.1).abs() < 1e-12, "{d} {dphi}");
        let (d, dphi) = step(&mut w, 1, [0.01, 0.15]);
        assert_eq!((d, dphi, w.rejected[turn]), (0.0, 0.0, 1));
        // R1 still turns at the scenario's 0.3 (its own 6 rad/min).
        let (_, dphi) = step(&mut w, 0, [0.0, 0.3]);
        assert!((dphi - 0.3).abs() < 1e-12 && w.rejected[turn] == 1, "{dphi}");
    }

    /// Robots at the 3 hunting points of evader 1 (r_s around it), reporting them.
    fn ringed(m: &mut HuntMission, centre: Vec2, n: usize, offset: f64) -> Vec<[f64; 3]> {
        let mut poses = vec![[0.0, 0.0, 0.0]; m.bodies];
        for (k, pose) in poses.iter_mut().enumerate().take(n) {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            let pt = centre + m.p.r_s * Vec2::new(a.cos(), a.sin());
            *pose = [pt.x + offset, pt.y, 0.0];
            m.observe(k as u32, [1.0, pt.x, pt.y, 0.0]);
        }
        poses
    }

    #[test]
    fn capture_needs_the_points_the_count_the_resources_and_enclosure() {
        let sc = example();
        // T1 needs 3 robots and {10,9,14,15,18,15}; robots 0..3 (R1, R2, R3) carry
        // {3,2,5,6,8,7} + {14,11,15,11,18,17} + {4,5,4,3,2,1} = {21,18,24,20,28,25}: enough.
        let mut m = HuntMission::new(&sc);
        let c = m.evaders[0].pos;
        let alive = vec![true; m.bodies];
        let poses = ringed(&mut m, c, 3, 0.0);
        assert_eq!(m.captured_now(0, &poses, &alive), Some(vec![0, 1, 2]));
        // 0.06 km off their points (tolerance 0.05): not yet.
        let poses = ringed(&mut m, c, 3, 0.06);
        assert_eq!(m.captured_now(0, &poses, &alive), None);
        // Two robots are too few for L_1 = 3.
        let mut m = HuntMission::new(&sc);
        let poses = ringed(&mut m, c, 2, 0.0);
        assert_eq!(m.captured_now(0, &poses, &alive), None);
        // Three robots bunched on one side (largest gap > pi) do not enclose it.
        let mut m = HuntMission::new(&sc);
        let mut poses = vec![[0.0; 3]; m.bodies];
        for (k, pose) in poses.iter_mut().enumerate().take(3) {
            let a = 0.3 * k as f64;
            let pt = c + m.p.r_s * Vec2::new(a.cos(), a.sin());
            *pose = [pt.x, pt.y, 0.0];
            m.observe(k as u32, [1.0, pt.x, pt.y, 0.0]);
        }
        assert_eq!(m.captured_now(0, &poses, &alive), None);
        // R1 + R3 + R4 ({3,2,5,6,8,7} + {4,5,4,3,2,1} + {5,4,3,2,6,5} = {12,11,12,11,16,13})
        // lack T1's 14 of type 3: no capture (2.6).
        let mut m = HuntMission::new(&sc);
        let mut poses = vec![[0.0; 3]; m.bodies];
        for (k, i) in [0usize, 2, 3].iter().enumerate() {
            let a = std::f64::consts::TAU * k as f64 / 3.0;
            let pt = c + m.p.r_s * Vec2::new(a.cos(), a.sin());
            poses[*i] = [pt.x, pt.y, 0.0];
            m.observe(*i as u32, [1.0, pt.x, pt.y, 0.0]);
        }
        assert_eq!(m.captured_now(0, &poses, &alive), None);
    }

    #[test]
    fn a_wall_closer_than_r_s_encloses_like_a_pursuer() {
        // T1 (L = 3, R1 + R2 + R3 cover E_1) moved onto the north wall (y = 10). Its three
        // robots stand on the r_s circle's arc below the wall at bearings -160, -90 and -20
        // degrees: among themselves the largest gap is 220 degrees (> pi, not enclosed), but
        // the wall's bearing (+90) splits it into 110 + 110.
        let sc = example();
        let alive = vec![true; 16];
        let place = |inside: bool| {
            let mut sc = sc.clone();
            sc.hunt_mut().params.hunting_points_inside_arena = inside;
            let mut m = HuntMission::new(&sc);
            m.evaders[0].pos = Vec2::new(5.0, 10.0);
            let c = m.evaders[0].pos;
            let mut poses = vec![[0.0; 3]; m.bodies];
            for (k, deg) in [-160.0f64, -90.0, -20.0].iter().enumerate() {
                let a = deg.to_radians();
                let pt = c + m.p.r_s * Vec2::new(a.cos(), a.sin());
                poses[k] = [pt.x, pt.y, 0.0];
                m.observe(k as u32, [1.0, pt.x, pt.y, 0.0]);
            }
            m.captured_now(0, &poses, &alive)
        };
        assert_eq!(place(true), Some(vec![0, 1, 2]));
        assert_eq!(place(false), None, "the printed rule: a 220-degree gap");
    }

    #[test]
    fn evaders_are_silent_flee_when_pursued_and_t5_appears_mid_run() {
        let sc = example();
        let mut m = HuntMission::new(&sc);
        let t5 = m.evaders.iter().position(|e| e.spec.id == 5).unwrap();
        assert_eq!(m.evaders[t5].appear_tick, 100); // 5 min at 0.05 min a tick
        let far = vec![[0.0, 0.0, 0.0]; m.bodies];
        let alive = vec![true; m.bodies];
        let mut s = Sense::zeroed();
        m.sense(0, [1.0, 1.0], &mut s);
        assert_eq!(s.entities().len(), 4, "T5 is not there yet");
        assert!(s
            .entities()
            .iter()
            .all(|e| e.kind == ENTITY_EVADER && e.flags & ENTITY_HAS_POS != 0));
        let mut ev = Vec::new();
        for k in 0..100 {
            m.update(k, &far, &alive, &mut ev);
        }
        // Nobody within 1.5 km of any evader: none moved.
        assert!(m
            .evaders
            .iter()
            .all(|e| e.pos == Vec2::new(e.spec.position[0], e.spec.position[1])));
        m.sense(0, [1.0, 1.0], &mut s);
        assert_eq!(s.entities().len(), 5, "T5 appears at tick 100");
        // A pursuer 1 km east of T2 (2.83, 4.48): T2 flees west at full speed 1.0 km/min.
        let mut near = far.clone();
        near[0] = [3.83, 4.48, 0.0];
        m.update(100, &near, &alive, &mut ev);
        let t2 = &m.evaders[1];
        assert!((t2.pos.x - (2.83 - 1.0 * 0.05)).abs() < 1e-12, "{:?}", t2.pos);
        assert!((t2.pos.y - 4.48).abs() < 1e-12);
        // The auctioneer senses nothing.
        m.sense(m.station, [5.0, 5.0], &mut s);
        assert_eq!(s.n_entities, 0);
    }
}
