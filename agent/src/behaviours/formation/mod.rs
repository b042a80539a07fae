//! The formation behaviour of docs/formation.md (Zhang et al. 2024): one robot's share of the
//! paper's pipeline, from its Sense frame and its radio inbox only.
//!
//! Per tick k:
//! 1. `listen`: statuses (position, velocity, slot) of the robots heard; a plan of a newer
//!    epoch (or of the same epoch from a lower coordinator) replaces the robot's; an
//!    assignment of its plan's epoch newer than the last replaces its slot.
//! 2. `coordinate` (spec 5 option (a)): the robot is the coordinator when its id is the lowest
//!    of those it heard within `formation.lost_after_ticks` ticks. The coordinator gathers
//!    the start positions (until it heard every live robot, Sense `alive_robots`, or
//!    `gather_ticks` passed), solves eq. (14) by branch-and-bound and broadcasts the plan
//!    (alpha, d, theta, the template points, members, sigma, lost robots) with an epoch, every
//!    tick. It re-plans with epoch + 1 when a member falls silent for `lost_after_ticks` (the
//!    pattern for the robots left: the lost robot's template point is dropped, its last
//!    position becomes an obstacle), when it hears a robot that is not a member, or when it
//!    takes over from a lost coordinator. Per step (`formation.reassignment = "per-step"`)
//!    it solves eq. (15) by the Hungarian method on the positions heard, extrapolated by
//!    their velocities over their age, and broadcasts the assignment with the plan's epoch
//!    and the tick.
//!    With `reassignment = "swaps"` there is no coordinator: the pattern is the fixed
//!    `formation.transform` every robot computes alike, robot i starts on slot i, and
//!    neighbours swap slots pairwise with a handshake (agent/src/formation/swaps.rs). When
//!    a robot dies (or a wreck blocks a slot) the robots elect a coordinator that re-plans
//!    for the robots left (replan.rs), and swaps resume on the new slots.
//! 3. `motion`: eq. (16) towards its slot, then ORCA (eqs. 17-26) against the robots its own
//!    sensors list (Sense `nearby`, within robot.neighbour_sensing_radius: positions and
//!    velocities), the arena's discs, the lost robots of the plan, the wrecks (dead robots)
//!    sensed in the Sense frame's obstacle points or heard of (wrecks.rs), and robots that
//!    vanished from `nearby` while well inside the sensing radius (static discs until seen
//!    again).
//! 4. `broadcast` its status; report its slot to the mission (Action `report`).
//!
//! Units: robot.v_max is per tick, so V_p = v_max / tau and the command is v tau.

mod checks;
pub mod compact;
pub mod detour;
pub mod gossip;
pub mod messages;
pub mod params;
pub mod relay;
mod relay_place;
mod relay_step;
mod replan;
mod replan_multihop;
mod shift_drop;
mod squeeze;
mod escape;
#[cfg(test)]
mod tests;
pub mod wrecks;

pub use messages::{Assign, CompactPlan, Msg, Plan, Status};
pub use params::{parse_params, Params};

use crate::formation::hungarian::{assign_targets, Hungarian};
use crate::formation::linear_program::{Selected, Selection};
use crate::formation::optimise::{optimise, optimise_without_rotation};
use crate::formation::orca::{orca_velocity_squeezing, Disc};
use crate::formation::swaps::{Message as SwapMessage, NeighbourView, SwapAgent};
use crate::formation::{Template, Transform};
use std::collections::BTreeMap;
use swarm::geometry::Vec2;
use swarm::scenario::{Check, ConfigError, Scenario};
use swarm::sections::formation::{
    FormationSection, PatternChoice, Reassignment, REPORT_NO_SLOT, REPORT_PLAN,
    REPORT_PLAN_SHAPE, REPORT_PLAN_SHIFT, STATE_COORDINATOR, STATE_IN_PLACE,
};
use swarm::{Behaviour, Command, Outbox, Received, Sense};

/// How far inside 2 r of a live robot a remembered wreck may lie and still be taken for a
/// wreck (the world keeps discs apart; ORCA's margin lets a live robot graze one). [chosen]
/// 0.05, ORCA's `orca_margin` default.
const WRECK_OVERLAP_TOLERANCE: f64 = 0.05;

/// The remembered wreck positions that can be wrecks: those not within 2 r (less
/// [`WRECK_OVERLAP_TOLERANCE`]) of this robot at `me` or of a live robot of its Sense frame.
fn real_wrecks(remembered: Vec<Vec2>, me: Vec2, live: &[Disc], robot_radius: f64) -> Vec<Vec2> {
    let clear = 2.0 * robot_radius - WRECK_OVERLAP_TOLERANCE;
    remembered
        .into_iter()
        .filter(|p| (p - me).norm() >= clear && live.iter().all(|o| (p - o.position).norm() >= clear))
        .collect()
}

/// The registry's name of this behaviour.
pub const NAME: &str = "formation";

/// The scenario sections it reads (a run refuses any other behaviour's or mission's section).
pub const SECTIONS: &[&str] = &["formation"];

/// Checks the formation behaviour's kernels against the scenario.
pub fn validate(sc: &Scenario, c: &Check) -> Result<(), ConfigError> {
    crate::behaviours::require_holonomic(sc, c, NAME)?;
    checks::validate(sc, c).and_then(|()| params::validate(sc, c))?;
    coordinator_plan_fits(sc, c)
}

/// The coordinator modes (per-step, one-shot) send the whole plan, members and sigma, in one
/// message: a swarm whose plan does not fit `radio.max_message_bytes` would never hear it and
/// stand still (measured: 500 robots at 512 bytes, 1 of 500 in place after 4,000 ticks).
fn coordinator_plan_fits(sc: &Scenario, c: &Check) -> Result<(), ConfigError> {
    let f = params::section(sc);
    if f.reassignment == Reassignment::Swaps {
        return Ok(());
    }
    if let Some(r) = parse_params(sc).ok().and_then(|p| p.relay) {
        return relay::check(sc, c, &r);
    }
    let need = compact::full_plan_len(sc.run.robots as usize, 0);
    if need <= sc.radio.max_message_bytes as usize {
        return Ok(());
    }
    let mode = match f.reassignment {
        Reassignment::OneShot => "one-shot",
        _ => "per-step",
    };
    Err(c.err(
        "formation.reassignment",
        format!(
            "\"{mode}\" sends the coordinator's plan for {} robots in one message ({need} bytes), \
             more than radio.max_message_bytes = {}: raise radio.max_message_bytes to at least \
             {need}, add a [formation.kernels.relay] table (the plan relayed in parts over many \
             hops), or use reassignment = \"swaps\" (allowed: \"per-step\", \"one-shot\", \"swaps\")",
            sc.run.robots, sc.radio.max_message_bytes
        ),
    ))
}

/// Writes every kernel parameter into `formation.kernels`, derived ones and defaults included.
pub fn resolve(sc: &mut Scenario) -> Result<(), ConfigError> {
    let bad = |message: String| ConfigError {
        source: "formation behaviour".into(),
        key: "formation.kernels".into(),
        message,
    };
    let p = parse_params(sc).map_err(bad)?;
    let mut f = params::section(sc);
    f.kernels = toml::Table::try_from(&p).map_err(|e| bad(e.to_string()))?;
    sc.set_formation(Some(f));
    Ok(())
}

/// Calls `v` with the formation robot's constructor.
pub fn dispatch<V: crate::BehaviourVisitor>(sc: &Scenario, v: V) -> V::Out {
    v.visit(&|i| Formation::new(sc, i))
}

/// What a robot last heard of another.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Heard {
    pos: Vec2,
    vel: Vec2,
    slot: i32,
    epoch: u32,
    /// Tick the status was sent at.
    tick: u64,
}

/// One robot of the formation.
pub struct Formation {
    robot: u32,
    p: Params,
    f: FormationSection,
    template: Vec<[f64; 2]>,
    discs: Vec<Disc>,
    heard: BTreeMap<u32, Heard>,
    plan: Option<Plan>,
    /// The slots of the plan (eq. 5 on its template points).
    targets: Vec<Vec2>,
    slot: Option<usize>,
    assign_seq: u64,
    /// Robots seen in `nearby` last tick, and those that vanished inside the sensing radius.
    last_nearby: BTreeMap<u32, Vec2>,
    ghosts: BTreeMap<u32, Vec2>,
    swap: Option<SwapAgent>,
    /// The epoch of the plan the handshake state `swap` is for.
    swap_epoch: Option<u32>,
    /// The tick this robot adopted its swaps-mode plan (it repeats it for `replan.relay_ticks`).
    adopted_at: u64,
    /// Swaps mode: since when a re-plan is needed, and the live count then.
    need_since: Option<(u64, u32)>,
    /// Dead robots' positions this robot knows (sensed or heard; the world's, exact).
    wrecks: Vec<Vec2>,
    statics: wrecks::StaticBoundaries,
    /// A robot on an older plan was heard: repeat the plan this tick.
    heard_older: bool,
    hungarian: Hungarian,
    first_tick: Option<u64>,
    /// Reports queued for the next ticks: a plan's (alpha, theta) and d follow its report.
    queued_reports: std::collections::VecDeque<[f64; 4]>,
    sensing_radius: f64,
    /// `robot.sensing_radius`: how far the Sense frame lists obstacle points and wrecks.
    obstacle_sensing_radius: f64,
    v_max_tick: f64,
    /// `FORMATION_TRACE` is set: print the measurement lines of [`Formation::trace_line`].
    trace: bool,
    /// run.robots (the gossip's bitmap of ids).
    robots: usize,
    /// Whether the swaps re-plan's full plan fits one message (else the multi-hop compact
    /// re-plan of replan_multihop.rs).
    full_plan_fits: bool,
    /// The most moves a compact plan carries within `radio.max_message_bytes` (worst case,
    /// compact.rs `moves_that_fit`).
    moves_fit: usize,
    /// The multi-hop re-plan's timeout (ticks from the need's start).
    replan_timeout: u64,
    /// The multi-hop re-plan's gossip for the current need.
    gathering: Option<gossip::Gathering>,
    /// The compact form of the plan held, when it came as one (relayed as it came).
    compact: Option<CompactPlan>,
    /// The relayed centralised mode's state (`formation.kernels.relay` present).
    relay: Option<relay_step::RelayState>,
    /// Squeezing past wrecks (squeeze.rs).
    squeeze: squeeze::Squeeze,
    /// Backing out of a notch of wrecks (escape.rs).
    escape: escape::Escape,
    /// The escape's way to the slot, as long as the last tick planned it (for the blocked
    /// swap's price, swaps.rs `set_path_length`).
    escape_length: std::cell::Cell<Option<f64>>,
    /// Where the partner of this robot's blocked swap stands while this robot makes way for
    /// it (swaps.rs `making_way`).
    make_way_from: Option<Vec2>,
}

impl Formation {
    pub fn new(sc: &Scenario, robot: u32) -> Formation {
        let p = parse_params(sc).unwrap_or_else(|e| panic!("{e} (the scenario was not validated)"));
        let f = params::section(sc);
        let template = f
            .template_points(sc.run.robots as usize)
            .unwrap_or_else(|e| panic!("{e} (the scenario was not validated)"));
        let diagonal = sc.arena.width.hypot(sc.arena.height);
        let hops = (diagonal / sc.radio.comm_radius.max(1e-9)).ceil() as u64;
        let replan_timeout = p.gather_ticks as u64 + p.replan.ticks_per_hop * hops;
        let full_plan_fits = compact::full_plan_fits(
            sc.run.robots as usize,
            p.replan.max_dead,
            sc.radio.max_message_bytes,
        );
        let moves_fit = compact::moves_that_fit(
            sc.run.robots as usize,
            p.replan.max_dead,
            sc.radio.max_message_bytes,
        );
        let relay_params = match f.reassignment {
            Reassignment::Swaps => None,
            _ => p.relay.clone(),
        };
        let discs = sc
            .arena
            .discs
            .iter()
            .map(|d| Disc {
                position: Vec2::new(d.centre[0], d.centre[1]),
                velocity: Vec2::zeros(),
                radius: d.radius,
            })
            .collect();
        Formation {
            robot,
            p,
            f,
            template,
            discs,
            heard: BTreeMap::new(),
            plan: None,
            targets: Vec::new(),
            slot: None,
            assign_seq: 0,
            last_nearby: BTreeMap::new(),
            ghosts: BTreeMap::new(),
            swap: None,
            swap_epoch: None,
            adopted_at: 0,
            need_since: None,
            wrecks: Vec::new(),
            statics: wrecks::StaticBoundaries::of(sc),
            heard_older: false,
            hungarian: Hungarian::new(),
            first_tick: None,
            queued_reports: Default::default(),
            sensing_radius: sc.robot.neighbour_sensing_radius,
            obstacle_sensing_radius: sc.robot.sensing_radius,
            v_max_tick: sc.robot.v_max,
            trace: std::env::var_os("FORMATION_TRACE").is_some(),
            robots: sc.run.robots as usize,
            full_plan_fits,
            moves_fit,
            replan_timeout,
            gathering: None,
            compact: None,
            squeeze: Default::default(),
            escape: Default::default(),
            escape_length: Default::default(),
            make_way_from: None,
            relay: relay_params.map(|r| relay_step::RelayState::new(robot, r, diagonal, sc.radio.comm_radius)),
        }
    }

    pub fn plan(&self) -> Option<&Plan> {
        self.plan.as_ref()
    }
    pub fn slot(&self) -> Option<usize> {
        self.slot
    }
    pub fn targets(&self) -> &[Vec2] {
        &self.targets
    }

    fn tau(&self) -> f64 {
        self.p.kernels.time_step
    }

    /// The robots heard within the lost window at tick k, by id.
    fn live_heard(&self, k: u64) -> BTreeMap<u32, Heard> {
        let window = self.f.lost_after_ticks as u64;
        self.heard
            .iter()
            .filter(|(_, h)| h.tick + window >= k)
            .map(|(i, h)| (*i, *h))
            .collect()
    }

    /// Prints a plan just solved (`solved`: plan, gap, nodes, as `solve` gives it; `what`:
    /// "plans" / "re-plans (swaps)", `extra`: more of the line), queues its shape and shift
    /// reports, installs it; the plan report (gap, seconds, REPORT_PLAN, nodes).
    fn adopt_solved(
        &mut self,
        k: u64,
        solved: (Plan, f64, usize),
        seconds: f64,
        what: &str,
        extra: String,
    ) -> [f64; 4] {
        let (plan, gap, nodes) = solved;
        eprintln!(
            "formation: robot {} {what} epoch {} at tick {k} for {} robots{extra}: alpha {:.4} d [{:.4}, {:.4}] theta {:.4}, gap {gap:.4}{}, {nodes} nodes, {seconds:.3} s",
            self.robot,
            plan.epoch,
            plan.points.len(),
            plan.transform[0],
            plan.transform[1],
            plan.transform[2],
            plan.transform[3],
            checks::gap_note(gap, what.starts_with("re-plans")),
        );
        let t = plan.transform;
        let epoch = plan.epoch as f64;
        self.queued_reports = [
            [t[0], t[3], REPORT_PLAN_SHAPE, epoch],
            [t[1], t[2], REPORT_PLAN_SHIFT, epoch],
        ]
        .into();
        self.install(plan);
        [gap, seconds, REPORT_PLAN, nodes as f64]
    }

    /// Adopts `plan`: the slots from eq. (5), this robot's slot from sigma.
    fn install(&mut self, plan: Plan) {
        let sub = self.sub_template(&plan.points);
        let t = transform_of(plan.transform);
        self.targets = t.targets(self.p.kernels.transform_reading, &sub);
        self.slot = plan
            .members
            .iter()
            .position(|m| *m == self.robot)
            .and_then(|i| plan.slots.get(i))
            .map(|s| *s as usize)
            .filter(|s| *s < self.targets.len());
        self.assign_seq = 0;
        self.plan = Some(plan);
        self.compact = None;
    }

    fn sub_template(&self, points: &[u16]) -> Template {
        Template {
            name: self.f.template_name.clone(),
            points: points
                .iter()
                .map(|j| self.template[*j as usize])
                .collect(),
        }
    }

    /// Whether `plan` should replace the robot's.
    fn better(&self, plan: &Plan) -> bool {
        match &self.plan {
            None => true,
            Some(mine) => {
                plan.epoch > mine.epoch
                    || (plan.epoch == mine.epoch && plan.coordinator < mine.coordinator)
            }
        }
    }

    /// Step 1.
    fn listen(&mut self, inbox: &[&Received<Msg>], swaps: &mut Vec<SwapMessage>, needs: &mut Vec<gossip::Need>) {
        let mut plans = Vec::new();
        let mut compacts = Vec::new();
        let mut assigns = Vec::new();
        let my_epoch = self.plan.as_ref().map(|p| p.epoch);
        self.heard_older = false;
        for r in inbox {
            match &r.msg {
                Msg::Status(s) => {
                    self.heard_older |= my_epoch.is_some_and(|e| s.epoch < e);
                    self.heard.insert(
                        r.from,
                        Heard {
                            pos: Vec2::new(s.pos[0], s.pos[1]),
                            vel: Vec2::new(s.vel[0], s.vel[1]),
                            slot: s.slot,
                            epoch: s.epoch,
                            tick: r.tick,
                        },
                    );
                    self.ghosts.remove(&r.from);
                }
                Msg::Plan(p) => plans.push(p.clone()),
                Msg::CompactPlan(c) => compacts.push(c.clone()),
                Msg::Need(n) => {
                    self.heard_older |= my_epoch.is_some_and(|e| n.epoch < e);
                    needs.push(n.clone());
                }
                Msg::Assign(a) => assigns.push((r.from, a.clone())),
                Msg::Wrecks(ws) => {
                    for w in ws {
                        wrecks::remember(&mut self.wrecks, Vec2::new(w[0], w[1]));
                    }
                }
                Msg::Propose {
                    to,
                    seq,
                    from_target,
                    to_target,
                    from_position,
                    deadline,
                    epoch,
                    blocked,
                    from_cost,
                } if *to == self.robot && Some(*epoch) == my_epoch => swaps.push(SwapMessage::Propose {
                    from: r.from as usize,
                    to: *to as usize,
                    seq: *seq,
                    from_target: *from_target as usize,
                    to_target: *to_target as usize,
                    from_position: *from_position,
                    deadline: *deadline,
                    blocked: *blocked,
                    from_cost: *from_cost,
                }),
                Msg::Reply {
                    to,
                    seq,
                    accepted,
                    epoch,
                } if *to == self.robot && Some(*epoch) == my_epoch => {
                    swaps.push(SwapMessage::Reply {
                        from: r.from as usize,
                        to: *to as usize,
                        seq: *seq,
                        accepted: *accepted,
                    })
                }
                _ => {}
            }
        }
        for p in plans {
            if self.better(&p) {
                self.install(p);
            }
        }
        for c in compacts {
            if self.better(&compact::plan_of(&c)) {
                self.install_compact(c);
            }
        }
        for (from, a) in assigns {
            let Some(plan) = &self.plan else { continue };
            if a.epoch != plan.epoch || from != plan.coordinator || a.seq <= self.assign_seq {
                continue;
            }
            if let Some(i) = plan.members.iter().position(|m| *m == self.robot) {
                if let Some(s) = a.slots.get(i) {
                    if (*s as usize) < self.targets.len() {
                        self.slot = Some(*s as usize);
                        self.assign_seq = a.seq;
                    }
                }
            }
        }
    }

    /// Robots that vanished from `nearby` well inside the sensing radius are dead (static).
    fn track_ghosts(&mut self, sense: &Sense, me: Vec2) {
        let now: BTreeMap<u32, Vec2> = sense.nearby[..sense.n_nearby as usize]
            .iter()
            .map(|n| (n.robot, Vec2::new(n.pos[0], n.pos[1])))
            .collect();
        // A live robot leaves the list only across its edge: at most one step of each apart
        // from it, plus a margin.
        let mut inside = self.sensing_radius - 2.0 * self.v_max_tick - 2.0 * self.p.kernels.robot_radius;
        // A full list holds only the nearest MAX_NEARBY: a live robot also leaves it when
        // others come nearer, so only one that was nearer than the list's farthest, by more
        // than both steps, has vanished (in a 500-robot crowd live robots were taken for dead).
        if sense.n_nearby as usize >= swarm::frames::MAX_NEARBY {
            let farthest = now.values().map(|p| (p - me).norm()).fold(0.0, f64::max);
            inside = inside.min(farthest - 2.0 * self.v_max_tick);
        }
        for (id, pos) in &self.last_nearby {
            if !now.contains_key(id) && (pos - me).norm() < inside {
                self.ghosts.insert(*id, *pos);
            }
        }
        for id in now.keys() {
            self.ghosts.remove(id);
        }
        self.last_nearby = now;
    }

    /// The position of a heard robot extrapolated to tick k.
    fn estimate(&self, h: &Heard, k: u64) -> Vec2 {
        h.pos + h.vel * (self.tau() * k.saturating_sub(h.tick) as f64)
    }

    /// Step 2 for the coordinator: returns the plan report when it solved this tick.
    fn coordinate(&mut self, k: u64, me: Vec2, alive: u32, out: &mut Outbox<Msg>) -> Option<[f64; 4]> {
        let live = self.live_heard(k);
        if live.keys().next().is_some_and(|low| *low < self.robot) {
            return None;
        }
        let first = *self.first_tick.get_or_insert(k);
        let mut report = None;
        let replan = match &self.plan {
            None => {
                live.len() as u32 + 1 >= alive || k >= first + self.p.gather_ticks as u64
            }
            Some(plan) => {
                plan.coordinator != self.robot
                    || plan
                        .members
                        .iter()
                        .any(|m| *m != self.robot && !live.contains_key(m))
                    || live.keys().any(|id| !plan.members.contains(id))
            }
        };
        if replan {
            let started = std::time::Instant::now();
            let solved = self.solve(k, me, &live);
            let seconds = started.elapsed().as_secs_f64();
            report = Some(self.adopt_solved(k, solved, seconds, "plans", String::new()));
        }
        let Some(plan) = self.plan.clone() else {
            return report;
        };
        if self.f.reassignment == Reassignment::PerStep && !replan {
            // Eq. (15) on the positions heard, extrapolated over their age.
            let positions: Vec<Vec2> = plan
                .members
                .iter()
                .map(|m| {
                    if *m == self.robot {
                        me
                    } else {
                        self.estimate(&live[m], k)
                    }
                })
                .collect();
            let mut sigma = Vec::new();
            if assign_targets(&positions, &self.targets, &mut self.hungarian, &mut sigma).is_ok() {
                let slots: Vec<u16> = sigma.iter().map(|s| *s as u16).collect();
                if let Some(i) = plan.members.iter().position(|m| *m == self.robot) {
                    self.slot = Some(sigma[i]);
                }
                self.assign_seq = k;
                out.broadcast(Msg::Assign(Assign {
                    epoch: plan.epoch,
                    seq: k,
                    slots,
                }));
            }
        }
        out.broadcast(Msg::Plan(plan));
        report
    }

    /// Solves the pattern for this robot and the live robots heard: (plan, gap, nodes).
    fn solve(&self, k: u64, me: Vec2, live: &BTreeMap<u32, Heard>) -> (Plan, f64, usize) {
        let mut members: Vec<u32> = live.keys().copied().collect();
        members.push(self.robot);
        members.sort_unstable();
        let positions: Vec<Vec2> = members
            .iter()
            .map(|m| {
                if *m == self.robot {
                    me
                } else {
                    self.estimate(&live[m], k)
                }
            })
            .collect();
        let mut dead = Vec::new();
        let mut points: Vec<u16> = Vec::new();
        let mut epoch = 1;
        if let Some(old) = &self.plan {
            epoch = old.epoch + 1;
            dead = old.dead.clone();
            // The slots the lost members held (their last status of this epoch, else sigma)
            // leave the pattern; every other template point stays.
            let mut lost_slots = Vec::new();
            for (i, m) in old.members.iter().enumerate() {
                if members.contains(m) {
                    continue;
                }
                let h = self.heard.get(m);
                if let Some(h) = h {
                    // Its last status was sent before its last move.
                    let at = h.pos + h.vel * self.tau();
                    dead.push([at.x, at.y]);
                }
                let held = h
                    .filter(|h| h.epoch == old.epoch && h.slot >= 0)
                    .map(|h| h.slot as usize)
                    .or_else(|| old.slots.get(i).map(|s| *s as usize));
                lost_slots.extend(held);
            }
            points = old
                .points
                .iter()
                .enumerate()
                .filter(|(j, _)| !lost_slots.contains(j))
                .map(|(_, p)| *p)
                .collect();
        }
        for j in 0..self.template.len() as u16 {
            if points.len() >= members.len() {
                break;
            }
            if !points.contains(&j) {
                points.push(j);
            }
        }
        points.truncate(members.len());
        points.sort_unstable();
        let sub = self.sub_template(&points);
        let mut params = self.p.kernels.clone();
        params.obstacle_centres.extend(dead.iter().copied());
        let solution = match self.f.pattern {
            PatternChoice::Optimise => optimise(&positions, &sub, &params).ok(),
            PatternChoice::NoRotation => optimise_without_rotation(&positions, &sub, &params).ok(),
            PatternChoice::Fixed => None,
        };
        let (transform, sigma, gap, nodes) = match solution {
            Some(s) => (
                [s.transform.alpha, s.transform.d[0], s.transform.d[1], s.transform.theta],
                s.assignment,
                s.gap,
                s.nodes,
            ),
            None => {
                // Fixed, or no feasible placement: formation.transform, assigned by Hungarian.
                let t = transform_of(self.f.transform);
                let targets = t.targets(params.transform_reading, &sub);
                let mut sigma = Vec::new();
                let mut h = Hungarian::new();
                if assign_targets(&positions, &targets, &mut h, &mut sigma).is_err() {
                    sigma = (0..members.len()).collect();
                }
                (self.f.transform, sigma, checks::no_plan_gap(self.f.pattern), 0)
            }
        };
        (
            Plan {
                epoch,
                coordinator: self.robot,
                transform,
                points,
                members,
                slots: sigma.iter().map(|s| *s as u16).collect(),
                dead,
            },
            gap,
            nodes,
        )
    }

    /// Step 2 for decentralised swaps: the fixed pattern, then one step of the handshake.
    fn swap_step(
        &mut self,
        k: u64,
        me: Vec2,
        alive: u32,
        inbox: &[SwapMessage],
        needs: &[gossip::Need],
        out: &mut Outbox<Msg>,
    ) -> Option<[f64; 4]> {
        if self.plan.is_none() {
            let n = self.template.len();
            self.install(Plan {
                epoch: 0,
                coordinator: u32::MAX,
                transform: self.f.transform,
                points: (0..n as u16).collect(),
                members: (0..n as u32).collect(),
                slots: (0..n as u16).collect(),
                dead: Vec::new(),
            });
        }
        let report = if self.full_plan_fits {
            self.replan_step(k, me, alive)
        } else {
            self.replan_multihop(k, alive, needs, out)
        };
        self.adopt_for_swaps(k, me);
        let plan = self.plan.as_ref().expect("installed above");
        let epoch = plan.epoch;
        if epoch > 0
            && (k < self.adopted_at + self.p.replan.relay_ticks
                || plan.coordinator == self.robot
                || self.heard_older)
        {
            match &self.compact {
                Some(c) => out.broadcast(Msg::CompactPlan(c.clone())),
                None => out.broadcast(Msg::Plan(plan.clone())),
            };
        }
        // Wrecks the plan was not made around: for the coordinator of the next re-plan.
        let news: Vec<[f64; 2]> = self
            .wrecks
            .iter()
            .filter(|w| !plan.dead.iter().any(|d| d[0] == w.x && d[1] == w.y))
            .map(|w| [w.x, w.y])
            .collect();
        if !news.is_empty() {
            out.broadcast(Msg::Wrecks(news));
        }
        let neighbours: Vec<NeighbourView> = self
            .live_heard(k)
            .iter()
            .filter(|(_, h)| h.slot >= 0 && h.epoch == epoch)
            .map(|(id, h)| NeighbourView {
                id: *id as usize,
                position: self.estimate(h, k),
                target: h.slot as usize,
                tick: h.tick,
            })
            .collect();
        // The dead this robot knows of (vanished from its sensors inside their radius): where
        // the wreck lies and the slot it last held, heard from its status.
        let wrecks: Vec<(Vec2, usize)> = self
            .ghosts
            .iter()
            .filter_map(|(id, at)| {
                let h = self.heard.get(id)?;
                (h.slot >= 0).then_some((*at, h.slot as usize))
            })
            .collect();
        let blocked_within = self.blocked_within();
        let Some(agent) = &mut self.swap else {
            return report;
        };
        // Not while a multi-hop re-plan gathers: its `held` set counts each robot's point once
        // (gossip.rs).
        if !wrecks.is_empty() && epoch == 0 && self.gathering.is_none() {
            agent.take_vacancy(&self.targets, &wrecks, &neighbours, blocked_within);
        }
        // Multi-hop re-plan: no new swap while gathering (min gain infinite: no proposal, every
        // new one rejected), so the handshakes in flight settle before the plan comes and the
        // robots' template points are a permutation when they assign themselves (without
        // this, 7 slots were doubled at 100 robots, kill 100:37: handshakes cut by the plan).
        let frozen;
        let swap_params = if self.gathering.is_some() {
            frozen = crate::formation::swaps::SwapParams {
                min_gain: f64::INFINITY,
                blocked: None,
                ..self.p.swaps.clone()
            };
            &frozen
        } else {
            &self.p.swaps
        };
        agent.set_path_length(self.escape_length.get().filter(|_| self.escape.on()));
        let msgs = agent.step(k, me, &self.targets, &neighbours, inbox, swap_params);
        self.slot = Some(agent.target);
        self.make_way_from = agent.making_way(k, &self.targets, &neighbours, swap_params);
        for m in msgs {
            let _ = match m {
                SwapMessage::Propose {
                    to,
                    seq,
                    from_target,
                    to_target,
                    from_position,
                    deadline,
                    blocked,
                    from_cost,
                    ..
                } => out.send(
                    to as u32,
                    Msg::Propose {
                        to: to as u32,
                        seq,
                        from_target: from_target as u32,
                        to_target: to_target as u32,
                        from_position,
                        deadline,
                        epoch,
                        blocked,
                        from_cost,
                    },
                ),
                SwapMessage::Reply {
                    to, seq, accepted, ..
                } => out.send(
                    to as u32,
                    Msg::Reply {
                        to: to as u32,
                        seq,
                        accepted,
                        epoch,
                    },
                ),
            };
        }
        report
    }

    /// Step 3: eq. (16) then ORCA; the velocity in units per second, and the distance to
    /// the nearest wreck ORCA saw.
    fn motion(&self, sense: &Sense, me: Vec2) -> (Vec2, f64) {
        let k = &self.p.kernels;
        let tau = k.time_step;
        let r = k.robot_radius + self.p.orca_margin;
        let mine = Disc {
            position: me,
            velocity: Vec2::new(sense.vel[0], sense.vel[1]) / tau,
            radius: r,
        };
        let robots: Vec<Disc> = sense.nearby[..sense.n_nearby as usize]
            .iter()
            .filter(|n| n.robot != self.robot)
            .map(|n| Disc {
                position: Vec2::new(n.pos[0], n.pos[1]),
                velocity: Vec2::new(n.vel[0], n.vel[1]) / tau,
                radius: r,
            })
            .collect();
        let mut obstacles = self.discs.clone();
        for o in &mut obstacles {
            o.radius += self.p.orca_margin;
        }
        let mut dead: Vec<Vec2> = self.wrecks.clone();
        for d in self.plan.iter().flat_map(|p| p.dead.iter()) {
            wrecks::remember(&mut dead, Vec2::new(d[0], d[1]));
        }
        // A wreck is a disc no live robot can stand within 2 r of: a remembered position
        // that close to this robot or to a robot the Sense frame shows alive is stale (a
        // robot taken for lost while alive, e.g. a coordinator out of its radio range), and
        // as a static disc over a live one it would leave ORCA no feasible velocity.
        let remembered: Vec<Vec2> = dead.into_iter().chain(self.ghosts.values().copied()).collect();
        let mut wrecks = real_wrecks(remembered, me, &robots, k.robot_radius);
        let squeezing = self.squeeze.on() || self.escape.on();
        if squeezing {
            let listed = sense.obstacle_points();
            let full = listed.len() >= swarm::frames::MAX_OBSTACLE_POINTS;
            let complete = squeeze::complete_radius(me, listed, full, self.obstacle_sensing_radius);
            wrecks = squeeze::trusted_wrecks(me, &wrecks, &self.statics.wrecks_in(sense), complete);
        }
        let wreck_discs = wrecks.iter().map(|pos| Disc {
            position: *pos,
            velocity: Vec2::zeros(),
            radius: r,
        });
        // Boxed in beside wrecks (squeeze.rs): they keep only their buffered cells, and so do
        // the arena's discs (static too: a cell at the true radii is exact for them; a robot
        // wedged between a wreck and a disc 5.05 apart, which it passes at the true radii
        // (5.0) but not with the disc's margin, stood still for good: docs/formation.md 9).
        let cell_only: Vec<Disc> = if squeezing {
            wreck_discs.chain(std::mem::take(&mut obstacles)).collect()
        } else {
            obstacles.extend(wreck_discs);
            Vec::new()
        };
        let preferred = self.preferred(me, &wrecks);
        let sel = orca_velocity_squeezing(&mine, preferred, &robots, &obstacles, &cell_only, k);
        if self.trace {
            self.trace_line(sense.tick, me, robots.len(), preferred, &sel);
        }
        (sel.velocity, squeeze::nearest(me, &wrecks))
    }
}

impl Formation {
    /// The preferred velocity: making way after a blocked swap (swaps.rs `making_way`), else
    /// out of a notch of wrecks (escape.rs), else eq. (16), steered round walls of wrecks in
    /// the swaps mode (detour.rs).
    fn preferred(&self, me: Vec2, wrecks: &[Vec2]) -> Vec2 {
        self.escape_length.set(None);
        let k = &self.p.kernels;
        let making_way = self.make_way_from.filter(|f| (me - f).norm() > 1e-9);
        let blocked = self.p.swaps.blocked.as_ref();
        if let (Some(from), Some(b)) = (making_way, blocked) {
            // Away from the partner, so that it can step into the slot this robot left (a
            // head-on pair in a packed pattern stood still for good: docs/formation.md 9),
            // until `make_way_steps` steps clear of ORCA's contact with it; then still.
            let reach = k.robot_radius + self.p.orca_margin;
            let clear = 2.0 * reach + b.make_way_steps * k.max_speed * k.time_step;
            return if (me - from).norm() < clear {
                (me - from).normalize() * (b.make_way_speed * k.max_speed)
            } else {
                Vec2::zeros()
            };
        }
        if self.escape.on() {
            return self.preferred_escaping(me, wrecks);
        }
        self.preferred_with_detour(me, wrecks)
    }

    /// The measurement of docs/formation.md 9 (environment variable `FORMATION_TRACE` set):
    /// one stderr line per robot every 10 ticks and at every tick ORCA had no feasible
    /// velocity: `TRACE tick robot x y slot slot_x slot_y selection neighbours busy
    /// pref_x pref_y v_x v_y` (busy: in a swap handshake).
    fn trace_line(&self, tick: u64, me: Vec2, neighbours: usize, preferred: Vec2, sel: &Selected) {
        if sel.selection == Selection::Feasible && !tick.is_multiple_of(10) {
            return;
        }
        let (sx, sy, s) = match self.slot {
            Some(s) => (self.targets[s].x, self.targets[s].y, s as i64),
            None => (0.0, 0.0, -1),
        };
        let busy = self.swap.as_ref().is_some_and(|a| a.is_busy());
        eprintln!(
            "TRACE {tick} {} {:.3} {:.3} {s} {sx:.3} {sy:.3} {:?} {neighbours} {busy} {:.3} {:.3} {:.3} {:.3} squeeze={} escape={}",
            self.robot, me.x, me.y, sel.selection, preferred.x, preferred.y, sel.velocity.x, sel.velocity.y,
            self.squeeze.on(), self.escape.on()
        );
    }
}

fn transform_of(t: [f64; 4]) -> Transform {
    Transform {
        alpha: t[0],
        d: [t[1], t[2]],
        theta: t[3],
    }
}

impl Behaviour for Formation {
    type Msg = Msg;

    fn step_refs(&mut self, sense: &Sense, inbox: &[&Received<Msg>], out: &mut Outbox<Msg>) -> Command {
        let k = sense.tick;
        let me = Vec2::new(sense.pos[0], sense.pos[1]);
        let mut swaps = Vec::new();
        let mut needs = Vec::new();
        self.listen(inbox, &mut swaps, &mut needs);
        self.track_ghosts(sense, me);
        for w in self.statics.wrecks_in(sense) {
            wrecks::remember(&mut self.wrecks, w);
        }
        // A restarted robot drives its body again: it is no wreck any more.
        let r = self.p.kernels.robot_radius;
        self.wrecks.retain(|w| {
            !sense
                .nearby()
                .iter()
                .any(|n| (Vec2::new(n.pos[0], n.pos[1]) - w).norm() < r)
        });
        let report = if self.f.reassignment == Reassignment::Swaps {
            self.swap_step(k, me, sense.alive_robots, &swaps, &needs, out)
        } else if self.relay.is_some() {
            let vel = Vec2::new(sense.vel[0], sense.vel[1]) / self.tau();
            self.relay_step(k, me, vel, sense.alive_robots, inbox, out)
        } else {
            self.coordinate(k, me, sense.alive_robots, out)
        };
        let coordinator = self.plan.as_ref().is_some_and(|p| p.coordinator == self.robot);
        let (v, nearest_wreck) = self.motion(sense, me);
        let tau = self.tau();
        let kp = &self.p.kernels;
        let seen = squeeze::Seen {
            speed: v.norm(),
            max_speed: kp.max_speed,
            to_slot: self.slot.map(|s| (self.targets[s] - me).norm()),
            epsilon: kp.epsilon,
            nearest_wreck,
            contact: 2.0 * (kp.robot_radius + self.p.orca_margin),
            reach: kp.max_speed * tau,
        };
        self.squeeze.update(&seen, self.p.squeeze_after_ticks);
        let held = seen.speed <= squeeze::HELD_SPEED * seen.max_speed;
        let away = seen.to_slot.is_some_and(|d| d > seen.epsilon);
        self.escape.update(self.squeeze.on(), held, away, self.p.escape.after_ticks);
        let mut cmd = v * tau;
        // The world refuses commands above v_max: keep rounding from crossing it.
        if cmd.norm() > self.v_max_tick {
            cmd *= self.v_max_tick / cmd.norm() * (1.0 - 1e-12);
        }
        let epoch = self.plan.as_ref().map_or(0, |p| p.epoch);
        out.broadcast(Msg::Status(Status {
            pos: sense.pos,
            vel: [cmd.x / tau, cmd.y / tau],
            slot: self.slot.map_or(-1, |s| s as i32),
            epoch,
        }));
        let in_place = self
            .slot
            .is_some_and(|s| (self.targets[s] - me).norm() <= self.p.kernels.epsilon);
        let report = report.or_else(|| self.queued_reports.pop_front()).unwrap_or(match self.slot {
            Some(s) => [self.targets[s].x, self.targets[s].y, s as f64, epoch as f64],
            None => [0.0, 0.0, REPORT_NO_SLOT, 0.0],
        });
        let state = if coordinator {
            STATE_COORDINATOR
        } else if in_place {
            STATE_IN_PLACE
        } else {
            0
        };
        Command {
            cmd: [cmd.x, cmd.y],
            events: state,
            report,
        }
    }
}
