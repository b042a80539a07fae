//! The multi-target search behaviour of docs/search.md (BSOA + TPEPSO and the SVF / EPSO / ARBA
//! baselines): the per-robot loop of spec 2.9 for one robot, from its Sense frame and its radio
//! inbox only.
//!
//! Per tick (messages heard were sent at the previous tick), one method of `Search` a step
//! (the letters are spec 2.9's):
//! 1. `arrival` (2g): a robot whose arrival sensor fired (ENTITY_DONE_BY_YOU) declares: it
//!    broadcasts the find for `declare_ticks` ticks and stands still for good (spec 5 item 8).
//! 2. `listen` (2a): found targets (own find, `Found` messages, and the gossiped found lists)
//!    are excluded; one status per robot heard.
//! 3. `own_signals`, `candidacy` (2b, 2c): Type I: own signals above I_min, roulette of
//!    eqs. (2)-(3) keeping the previous choice. Otherwise Type II: the subgroup of the nearest
//!    Type I robot heard within R_cm.
//! 4. `closed_loop_adjustment` (2d, Table 1) over itself and the candidates of the same target
//!    it heard: kept -> cooperative, dropped -> roaming.
//! 5. `subgroup_memory` (2e): pb_i and sgb (fitness = own I_ij; sgb from the members' pbs
//!    heard).
//! 6. `cooperative_velocity` (2e): T_est from >= 3 detections (own and heard) via the
//!    calibration inverse (`target_estimate`, mode *T), eq. (11) (modes *T, *E) or the bat
//!    rule of search/arba.rs (modes *A), then `subgroup_separation`.
//!    `roaming_velocity` (2e): eq. (5) repulsion of the two nearest robots heard, heading kept
//!    without force.
//! 7. `obstacle_layer` (2f): BSOA or SVF on the desired velocity, every tick, in every state.
//! 8. `broadcast` (2b): the status (position, detections, candidacy, pb, found list).
//!
//! Choices where the paper is silent (each is a field of [`Params`] or noted here):
//! * Messages: one `Status` per tick per active robot (8 + ~20 bytes per detection / found id);
//!   a finder sends `Found` for `declare_ticks` ticks, then nothing; every status gossips the
//!   found targets the sender knows, so a lost declaration is made up for.
//! * Candidacy vs membership: a robot announces its *candidacy* (Type I with its signal, or
//!   Type II with its communicating robot and distance) and ranks itself by Table 1 against the
//!   candidacies of the same target heard last tick; dropped candidates roam but stay
//!   candidates, so they move in when a member leaves (the dynamic adjustment of paper 5.1).
//!   Type II robots attach to any Type I candidate heard (not only kept ones).
//! * pb_i = best own measurement since the robot joined (paper 3.3): empty at every join, so a
//!   Type II robot has no c1 term until it senses the target. sgb = best pb announced by
//!   members of the same target heard, running maximum; it survives short gaps
//!   (`keep_subgroup_best_across_gaps`).
//! * T_est uses every detection of the target above I_min heard last tick plus the own one
//!   (members or not); fewer than `estimator.min_detectors` (3): no c3 term (spec 5 item 14).
//! * Initial velocity: random heading at V_max (stream 20); roaming keeps the heading of the
//!   last commanded (post-avoidance) velocity when no robot is within 2 L_R.
//! * Cooperative robots ignore obstacle points beyond their estimated target distance
//!   (`goal_horizon_margin`) and keep apart by eq. (5) within `subgroup_separation`.
//! * The finder stands still for good and falls silent (spec 5 item 8).
//! * ARBA (modes BA, SA) replaces eq. (11) for cooperative robots by the bat rule of
//!   search/arba.rs with X* = sgb (from the pbs heard, as for TPEPSO) and fitness = own I_ij;
//!   everything else (roaming, roulette, Type II attachment, the closed-loop adjustment,
//!   `subgroup_separation`, the obstacle layer B or S) is as in the other modes, because Table 3
//!   swaps only the search method. ARBA's own obstacle-avoidance term is the mode's obstacle
//!   layer. Its draws come from a stream of their own (24); the bat is new whenever the
//!   subgroup memory is (a new target).

pub mod messages;
pub mod params;

pub use messages::{Candidacy, Msg, Status, WireRole};
pub use params::{
    parse_mode, parse_params, validate_search, ObstacleLayer, Params, SearchLayer, WallRule,
};

use crate::kernels::calibration::{self, Calibration};
use crate::kernels::estimator::{self, Detection};
use crate::kernels::subgroup::{self, Member, Role};
use crate::kernels::{arba, bsoa, svf, tpepso};
use crate::section::SearchScenario;
use crate::section::{STATE_COOPERATIVE, STATE_DECLARED};
use agent::kernels::virtual_force;
use messages::{pack, unpack, TargetSet};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;
use std::collections::BTreeSet;
use std::sync::{Arc, Mutex};
use swarm::frames::{ENTITY_DONE_BY_YOU, STATE_DEFAULT as STATE_ROAMING};
use swarm::geometry::{clamp_norm, Vec2};
use swarm::scenario::Scenario;
use swarm::scenario::{Check, ConfigError};
use swarm::streams::rng as robot_rng;
use swarm::{Behaviour, Command, Outbox, Received, Sense};

/// The registry's name of this behaviour.
pub const NAME: &str = "search";

/// The scenario sections it reads (a run refuses any other behaviour's or mission's section).
pub const SECTIONS: &[&str] = &["search"];

/// Checks the search behaviour's mode and kernels (`search.mode`, `search.kernels`) against
/// the scenario.
pub fn validate(sc: &Scenario, c: &Check) -> Result<(), ConfigError> {
    agent::behaviours::require_holonomic(sc, c, NAME)?;
    params::validate(sc, c)
}

/// Writes every kernel parameter into `search.kernels`, defaults included, so the run's
/// resolved scenario.toml lists each value the algorithms use (the kernels' defaults live in
/// code, with their sources, in params.rs and search/*.rs).
pub fn resolve(sc: &mut Scenario) -> Result<(), ConfigError> {
    let bad = |message: String| ConfigError {
        source: "search behaviour".into(),
        key: "search.kernels".into(),
        message,
    };
    let p = parse_params(sc).map_err(bad)?;
    sc.search_mut().kernels = toml::Table::try_from(&p).map_err(|e| bad(e.to_string()))?;
    Ok(())
}

/// Calls `v` with the search robot's constructor.
pub fn dispatch<V: swarm::plugin::BehaviourVisitor>(sc: &Scenario, v: V) -> V::Out {
    v.visit(&|i| Search::new(sc, i))
}

/// Event flag (above the display-state byte) set on the tick a robot declares a find.
pub const EVENT_TARGET_DECLARED: u32 = 1 << 8;

/// Random streams used by this behaviour (swarm::streams names every stream of a run).
use swarm::streams::{
    SEARCH_BAT as STREAM_BAT, SEARCH_CALIBRATION as STREAM_CALIBRATION,
    SEARCH_HEADING as STREAM_HEADING, SEARCH_PSO as STREAM_PSO, SEARCH_ROULETTE as STREAM_ROULETTE,
};

/// The robot's state (paper 2.3, Fig. 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mode {
    /// Roaming search by virtual force.
    Roaming,
    /// Member of the subgroup of `target` after the closed-loop adjustment.
    Cooperative { target: u32, role: Role },
    /// Found `target`; stands still for good.
    Declared { target: u32 },
}

/// What a robot remembers about its subgroup's target.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Memory {
    target: u32,
    pb: Option<(Vec2, f64)>,
    sgb: Option<(Vec2, f64)>,
}

/// One robot of the search.
pub struct Search {
    robot: u32,
    p: Params,
    v_max: f64,
    /// The search area [0, width] x [0, height] (Table 4), known to every robot; its
    /// obstacles are not.
    arena: (f64, f64),
    obstacle: ObstacleLayer,
    layer: SearchLayer,
    cal: Arc<Calibration>,
    rng_roulette: ChaCha8Rng,
    rng_pso: ChaCha8Rng,
    rng_bat: ChaCha8Rng,
    mode: Mode,
    /// Targets known to be found.
    found: BTreeSet<u32>,
    /// The Type I choice of the previous tick (eqs. 2-3 keep it while it is a candidate).
    choice: Option<u32>,
    memory: Option<Memory>,
    /// V_i(t) as commanded last tick (after obstacle avoidance); roaming keeps its heading.
    last_vel: Vec2,
    sf: bsoa::Sense,
    follow: svf::Follow,
    /// ARBA's per-robot state (modes *A), fresh whenever the subgroup memory is.
    bat: arba::Bat,
    declare_left: u32,
    /// Last T_est (for inspection and tests).
    last_estimate: Option<Vec2>,
    /// Last status broadcast (for inspection and tests).
    last_status: Option<Status>,
}

impl Search {
    /// The behaviour for `robot`, with the scenario's (validated) mode and kernels.
    pub fn new(sc: &Scenario, robot: u32) -> Search {
        let p = parse_params(sc).unwrap_or_else(|e| panic!("{e} (the scenario was not validated)"));
        Search::with_params(sc, robot, p)
    }

    /// The behaviour with explicit parameters (the mode still comes from the scenario).
    pub fn with_params(sc: &Scenario, robot: u32, p: Params) -> Search {
        let (obstacle, layer) = parse_mode(&sc.search().mode)
            .unwrap_or_else(|e| panic!("{e} (the scenario was not validated)"));
        let seed = sc.run.seed;
        // Initial velocity: a random heading at V_max. [chosen] spec 5 item 3.
        let a = robot_rng(seed, robot, STREAM_HEADING)
            .gen_range(-std::f64::consts::PI..std::f64::consts::PI);
        let v_max = sc.robot.v_max;
        // Offline calibration (paper 3.2), each robot with its own measurements.
        let cal = calibration_of(&p.calibration, seed, robot);
        Search {
            robot,
            v_max,
            arena: (sc.arena.width, sc.arena.height),
            obstacle,
            layer,
            cal,
            rng_roulette: robot_rng(seed, robot, STREAM_ROULETTE),
            rng_pso: robot_rng(seed, robot, STREAM_PSO),
            rng_bat: robot_rng(seed, robot, STREAM_BAT),
            mode: Mode::Roaming,
            found: BTreeSet::new(),
            choice: None,
            memory: None,
            last_vel: Vec2::new(a.cos(), a.sin()) * v_max,
            sf: bsoa::Sense::None,
            follow: svf::Follow::None,
            bat: arba::Bat::new(&p.arba),
            declare_left: 0,
            last_estimate: None,
            last_status: None,
            p,
        }
    }

    pub fn mode(&self) -> Mode {
        self.mode
    }
    pub fn found_targets(&self) -> &BTreeSet<u32> {
        &self.found
    }
    pub fn last_estimate(&self) -> Option<Vec2> {
        self.last_estimate
    }
    pub fn last_status(&self) -> Option<&Status> {
        self.last_status.as_ref()
    }
    pub fn personal_best(&self) -> Option<(Vec2, f64)> {
        self.memory.and_then(|m| m.pb)
    }
    pub fn subgroup_best(&self) -> Option<(Vec2, f64)> {
        self.memory.and_then(|m| m.sgb)
    }

    fn found_list(&self) -> TargetSet {
        TargetSet::from_sorted(self.found.iter().copied())
    }

    /// Step of a robot that has declared: silent after `declare_ticks` broadcasts, still.
    fn declared_step(&mut self, target: u32, out: &mut Outbox<Msg>, events: u32) -> Command {
        if self.declare_left > 0 {
            self.declare_left -= 1;
            out.broadcast(Msg::Found {
                target,
                found: self.found_list(),
            });
        }
        self.last_vel = Vec2::zeros();
        Command {
            cmd: [0.0, 0.0],
            events: STATE_DECLARED | events,
            ..Command::default()
        }
    }

    /// The candidacy of this tick: Type I for the chosen target, else Type II of the nearest
    /// Type I robot heard within R_cm.
    fn candidacy(
        &mut self,
        me: &Vec2,
        signals: &[(usize, f64)],
        heard: &[(u32, &Status)],
    ) -> Option<(u32, Role, Option<u32>)> {
        let prev = self
            .choice
            .filter(|t| !self.found.contains(t))
            .map(|t| t as usize);
        self.choice =
            subgroup::choose_target(signals, prev, &self.p.subgroup, &mut self.rng_roulette)
                .map(|t| t as u32);
        if let Some(t) = self.choice {
            let signal = signals
                .iter()
                .find(|(id, _)| *id as u32 == t)
                .map(|s| s.1)
                .unwrap_or(0.0);
            return Some((t, Role::TypeI { signal }, None));
        }
        let type_i: Vec<(usize, Vec2, u32)> = heard
            .iter()
            .filter_map(|(from, st)| match &st.candidacy {
                Some(Candidacy {
                    target,
                    role: WireRole::TypeI { .. },
                    ..
                }) if !self.found.contains(target) => {
                    let q = unpack(st.pos);
                    Some((*from as usize, Vec2::new(q[0], q[1]), *target))
                }
                _ => None,
            })
            .collect();
        let list: Vec<(usize, Vec2)> = type_i.iter().map(|(i, x, _)| (*i, *x)).collect();
        let (comm, d) = subgroup::communicating_robot(me, &list, &self.p.subgroup)?;
        let target = type_i.iter().find(|(i, _, _)| *i == comm)?.2;
        Some((
            target,
            Role::TypeII {
                distance_to_communicator: d,
            },
            Some(comm as u32),
        ))
    }
}

/// Offline calibrations this process has built, by (seed, robot, parameters as bits).
///
/// A calibration is 10,000 noisy measurements (100 distances x 100 repeats, paper 3.2) from
/// the robot's own seeded stream: a pure function of these, and ~0.5 ms each. An experiment
/// grid builds the same ones again and again (robot r with seed s is the same robot in every
/// mode and at every N): 54,000 builds for the 900 runs of Table 5, 3,000 of them different.
/// Built once per process instead; the table is the same bits either way.
type CalibrationKey = (u64, u32, [u64; 7]);
static CALIBRATIONS: Mutex<BTreeMap<CalibrationKey, Arc<Calibration>>> =
    Mutex::new(BTreeMap::new());
/// Calibrations kept before the cache starts again (each ~2 KiB). [chosen]
const MAX_CACHED_CALIBRATIONS: usize = 20_000;

fn calibration_of(p: &calibration::Params, seed: u64, robot: u32) -> Arc<Calibration> {
    let key = (
        seed,
        robot,
        [
            p.m.to_bits(),
            p.q.to_bits(),
            p.noise_sigma.to_bits(),
            p.l_t.to_bits(),
            p.d_min.to_bits(),
            p.n_distances as u64,
            p.repeats as u64,
        ],
    );
    let cache = || CALIBRATIONS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(c) = cache().get(&key) {
        return c.clone();
    }
    let built = Arc::new(Calibration::build(
        p,
        &mut robot_rng(seed, robot, STREAM_CALIBRATION),
    ));
    let mut m = cache();
    if m.len() >= MAX_CACHED_CALIBRATIONS {
        m.clear();
    }
    m.insert(key, built.clone());
    built
}

/// `v` with its component into a wall reversed, for each wall of [0, w] x [0, h] nearer than
/// `reach` that `v` heads into (the `reflect` wall rule).
fn reflect_off_walls(x: Vec2, mut v: Vec2, reach: f64, w: f64, h: f64) -> Vec2 {
    if (x.x < reach && v.x < 0.0) || (w - x.x < reach && v.x > 0.0) {
        v.x = -v.x;
    }
    if (x.y < reach && v.y < 0.0) || (h - x.y < reach && v.y > 0.0) {
        v.y = -v.y;
    }
    v
}

/// Positions of the robots heard (sent last tick), in sender order.
fn heard_positions(heard: &[(u32, &Status)]) -> Vec<Vec2> {
    heard
        .iter()
        .map(|(_, st)| {
            let q = unpack(st.pos);
            Vec2::new(q[0], q[1])
        })
        .collect()
}

fn wire_role(role: Role, communicator: Option<u32>) -> WireRole {
    match role {
        Role::TypeI { signal } => WireRole::TypeI {
            signal: signal as f32,
        },
        Role::TypeII {
            distance_to_communicator,
        } => WireRole::TypeII {
            communicator: communicator.unwrap_or(u32::MAX),
            distance: distance_to_communicator as f32,
        },
    }
}

fn role_of(w: WireRole) -> Role {
    match w {
        WireRole::TypeI { signal } => Role::TypeI {
            signal: signal as f64,
        },
        WireRole::TypeII { distance, .. } => Role::TypeII {
            distance_to_communicator: distance as f64,
        },
    }
}

/// The subgroup bests a kept member moves by (pb_i and sgb, TPEPSO's memory) and its own
/// signal of the target.
#[derive(Debug, Clone, Copy)]
struct Bests {
    /// The own signal I_ij of the target, if sensed at all.
    own: Option<f64>,
    /// The fitness of this tick (ARBA's): own I_ij, 0 without a signal (eq. 1).
    fitness: f64,
    /// pb_i (position, fitness); None until the robot has measured the target since it
    /// joined (then the c1 term of eq. 11 is absent).
    pb: Option<(Vec2, f64)>,
    /// sgb (position, fitness); None while no member's pb is known (no c2 term).
    sgb: Option<(Vec2, f64)>,
}

/// The paper's loop of spec 2.9, one step of one robot, in the order [`Behaviour::step_refs`]
/// calls them.
impl Search {
    /// Step 2g (spec 5 item 8): the arrival sensor fired at the last move (ENTITY_DONE_BY_YOU)
    /// for the returned target (the lowest id if several): every target it fired for is found,
    /// the robot declares and forgets its subgroup.
    fn arrival(&mut self, s: &Sense) -> Option<u32> {
        let t = s
            .entities()
            .iter()
            .filter(|g| g.flags & ENTITY_DONE_BY_YOU != 0)
            .map(|g| g.id)
            .min()?;
        for g in s.entities() {
            if g.flags & ENTITY_DONE_BY_YOU != 0 {
                self.found.insert(g.id);
            }
        }
        self.mode = Mode::Declared { target: t };
        self.memory = None;
        self.declare_left = self.p.declare_ticks;
        Some(t)
    }

    /// Step 2a, the radio half (what robots within R_cm said last tick): takes the found
    /// targets of every `Found` and every status's gossip, and returns the statuses of the
    /// other robots, one per sender (the last; the inbox is ordered by sender, then sequence).
    fn listen<'a>(&mut self, inbox: &[&'a Received<Msg>]) -> Vec<(u32, &'a Status)> {
        let mut heard: Vec<(u32, &Status)> = Vec::with_capacity(inbox.len());
        // Most statuses gossip targets this robot already knows: a sorted-slice check skips
        // the set inserts (which would change nothing).
        let mut known = self.found_list();
        for r in inbox {
            match &r.msg {
                Msg::Found { target, found } => {
                    self.found.insert(*target);
                    self.found.extend(found.iter());
                    known = self.found_list();
                }
                Msg::Status(st) => {
                    if !st.found.is_subset(&known) {
                        self.found.extend(st.found.iter());
                        known = self.found_list();
                    }
                    if r.from != self.robot {
                        heard.push((r.from, st));
                    }
                }
            }
        }
        // One status per sender: keep the last (highest sequence).
        heard.reverse();
        heard.dedup_by_key(|(from, _)| *from);
        heard.reverse();
        heard
    }

    /// Step 2a, the sensor half: the own signals I_ij (eq. 33) of targets not known to be
    /// found, as (target, intensity).
    fn own_signals(&self, s: &Sense) -> Vec<(usize, f64)> {
        s.entities()
            .iter()
            .filter(|g| g.flags == 0 && !self.found.contains(&g.id))
            .map(|g| (g.id as usize, g.value))
            .collect()
    }

    /// Step 2d, the closed-loop adjustment (Table 1) over this robot and the candidacies for
    /// the same target heard last tick: is this robot kept in the subgroup (cut to g_max)?
    /// Table 1's ranking, of which this robot needs only its own place.
    fn closed_loop_adjustment(&self, target: u32, role: Role, heard: &[(u32, &Status)]) -> bool {
        let mut members = vec![Member {
            robot: self.robot as usize,
            role,
        }];
        members.extend(heard.iter().filter_map(|(from, st)| {
            st.candidacy
                .as_ref()
                .filter(|c| c.target == target)
                .map(|c| Member {
                    robot: *from as usize,
                    role: role_of(c.role),
                })
        }));
        subgroup::is_kept(&members, 0, &self.p.subgroup)
    }

    /// Step 2e, the memory half (TPEPSO's pb_i and sgb, eq. 11). A memory of a found target
    /// is forgotten. pb_i is "the best since the robot joined the subgroup" (paper 3.3,
    /// 加入子联盟后的历史最优): it starts empty at every join (a new target, or the same one
    /// after a drop) and holds only positions where the robot measured the target itself
    /// (fitness = own I_ij); a robot that has not measured it yet has no pb_i and no c1 term.
    /// sgb is the subgroup's best: the running best of pb_i and the members' pbs heard; it
    /// survives a drop while the target stays the same if `keep_subgroup_best_across_gaps`.
    /// A fresh memory (new target) also starts a fresh ARBA bat. Returns the bests of a kept
    /// member.
    fn subgroup_memory(
        &mut self,
        kept: Option<u32>,
        me: Vec2,
        signals: &[(usize, f64)],
        heard: &[(u32, &Status)],
    ) -> Option<Bests> {
        let was_member_of = match self.mode {
            Mode::Cooperative { target, .. } => Some(target),
            _ => None,
        };
        if let Some(m) = self.memory {
            if self.found.contains(&m.target) {
                self.memory = None;
            }
        }
        let keep_sgb = self.p.keep_subgroup_best_across_gaps;
        let Some(t) = kept else {
            match self.memory.as_mut() {
                Some(m) if keep_sgb => m.pb = None,
                _ => self.memory = None,
            }
            return None;
        };
        match self.memory.as_mut() {
            Some(m) if m.target == t => {
                if was_member_of != Some(t) {
                    // Joined again: pb_i since this join; sgb kept only if asked.
                    m.pb = None;
                    if !keep_sgb {
                        m.sgb = None;
                    }
                }
            }
            _ => {
                self.memory = Some(Memory {
                    target: t,
                    pb: None,
                    sgb: None,
                });
                self.bat = arba::Bat::new(&self.p.arba);
            }
        }
        let own = signals.iter().find(|(id, _)| *id as u32 == t).map(|x| x.1);
        let mem = self.memory.as_mut().expect("set above");
        if let Some(i) = own {
            tpepso::update_best(&mut mem.pb, me, i);
        }
        if let Some((q, f)) = mem.pb {
            tpepso::update_best(&mut mem.sgb, q, f);
        }
        for (_, st) in heard {
            if let Some(c) = &st.candidacy {
                if c.target == t && c.member {
                    if let Some((q, f)) = c.pb {
                        let q = unpack(q);
                        tpepso::update_best(&mut mem.sgb, Vec2::new(q[0], q[1]), f as f64);
                    }
                }
            }
        }
        Some(Bests {
            own,
            // The signal is 0 where the target is not sensed (eq. 1).
            fitness: own.unwrap_or(0.0),
            pb: mem.pb,
            sgb: mem.sgb,
        })
    }

    /// Step 2e, T_est (eqs. 6-10): the target position from the own detection and those of
    /// `target` heard, each above I_min, distances by the calibration inverse G^{-1} (eq. 6);
    /// None below `estimator.min_detectors` (spec 5 item 14).
    fn target_estimate(
        &self,
        target: u32,
        me: Vec2,
        own: Option<f64>,
        heard: &[(u32, &Status)],
    ) -> Option<Vec2> {
        let i_min = self.p.subgroup.i_min;
        let mut dets: Vec<Detection> = Vec::new();
        if let Some(i) = own.filter(|i| *i > i_min) {
            dets.push(Detection {
                position: me,
                distance: self.cal.inverse(i),
                signal: i,
            });
        }
        for (_, st) in heard {
            for &(tt, i) in &st.detections {
                let i = i as f64;
                if tt == target && i > i_min {
                    let q = unpack(st.pos);
                    dets.push(Detection {
                        position: Vec2::new(q[0], q[1]),
                        distance: self.cal.inverse(i),
                        signal: i,
                    });
                }
            }
        }
        estimator::estimate(&dets, &self.p.estimator).map(|e| e.position)
    }

    /// Step 2e, cooperative velocity of a kept member: V_if by eq. (11) (TPEPSO with T_est in
    /// modes *T, EPSO without it in modes *E) or by ARBA's bat rule (modes *A), then kept
    /// apart from the robots heard by eq. (5) within `subgroup_separation`. Returns V_if and
    /// the own calibrated distance to the target if sensed (the obstacle layer's horizon).
    fn cooperative_velocity(
        &mut self,
        s: &Sense,
        me: Vec2,
        (target, role): (u32, Role),
        b: Bests,
        heard: &[(u32, &Status)],
    ) -> (Vec2, Option<f64>) {
        let i_min = self.p.subgroup.i_min;
        let horizon = b.own.filter(|i| *i > i_min).map(|i| self.cal.inverse(i));
        let estimate = if self.layer == SearchLayer::Tpepso {
            self.target_estimate(target, me, b.own, heard)
        } else {
            None
        };
        self.last_estimate = estimate;
        let state = tpepso::State {
            position: me,
            velocity: Vec2::new(s.vel[0], s.vel[1]),
            // A term without its best is absent (its best is the robot's own position).
            personal_best: b.pb.map_or(me, |p| p.0),
            subgroup_best: b.sgb.map_or(me, |g| g.0),
            target_estimate: estimate,
        };
        self.mode = Mode::Cooperative { target, role };
        let v = match self.layer {
            SearchLayer::Arba => arba::desired_velocity(
                &mut self.bat,
                me,
                state.velocity,
                state.subgroup_best,
                b.fitness,
                &self.p.arba,
                &mut self.rng_bat,
            ),
            layer => {
                let variant = if layer == SearchLayer::Tpepso {
                    tpepso::Variant::Tpepso
                } else {
                    tpepso::Variant::Epso
                };
                tpepso::desired_velocity(&state, variant, &self.p.tpepso, &mut self.rng_pso)
            }
        };
        (self.subgroup_separation(v, me, heard), horizon)
    }

    /// [chosen] Members keep apart: eq. (5) repulsion of the two nearest robots heard with
    /// L_R = `subgroup_separation` / 2 added to V_if, within V_max (0: off).
    fn subgroup_separation(&self, v: Vec2, me: Vec2, heard: &[(u32, &Status)]) -> Vec2 {
        if self.p.subgroup_separation > 0.0 {
            let others = heard_positions(heard);
            let f = virtual_force::Params {
                l_r: self.p.subgroup_separation / 2.0,
                ..self.p.virtual_force.clone()
            };
            clamp_norm(
                v + virtual_force::roaming_force(&me, &others, &f),
                self.v_max,
            )
        } else {
            v
        }
    }

    /// Step 2e, roaming velocity (paper 3.1, Fig. 2): V_if = V_max along f_vr1 + f_vr2, the
    /// eq. (5) repulsion of the two nearest robots heard; the heading of the last commanded
    /// velocity without a force (spec 5 item 5).
    /// The wall rule (`wall_rule`, spec 5 item 6) adds the walls' mirror images to the robots
    /// heard, or reflects the result off a wall within L_R.
    fn roaming_velocity(&mut self, me: Vec2, heard: &[(u32, &Status)]) -> Vec2 {
        self.mode = Mode::Roaming;
        let mut others = heard_positions(heard);
        let (w, h) = self.arena;
        if self.p.wall_rule == WallRule::Mirror {
            others.extend(virtual_force::wall_mirrors(&me, w, h));
        }
        let v =
            virtual_force::roaming_velocity(&me, &others, &self.last_vel, &self.p.virtual_force);
        if self.p.wall_rule == WallRule::Reflect {
            reflect_off_walls(me, v, self.p.virtual_force.l_r, w, h)
        } else {
            v
        }
    }

    /// Step 2f, the obstacle layer, every tick and in every state: BSOA (Table 2, eqs. 12-22)
    /// or SVF turns V_if into V_i(t+1), at most V_max (eq. 4; a non-finite result stands
    /// still). A cooperative robot ignores obstacle points beyond its calibrated distance to
    /// the target plus `goal_horizon_margin`. Remembers V_i(t+1) for roaming.
    fn obstacle_layer(&mut self, s: &Sense, me: Vec2, v_if: Vec2, horizon: Option<f64>) -> Vec2 {
        let horizon = match (self.mode, horizon) {
            (Mode::Cooperative { .. }, Some(d)) if self.p.goal_horizon_margin >= 0.0 => {
                d + self.p.goal_horizon_margin
            }
            _ => f64::INFINITY,
        };
        let sensed = s.obstacle_points().iter().map(|q| Vec2::new(q[0], q[1]));
        let v = match self.obstacle {
            ObstacleLayer::Bsoa => {
                let o = bsoa::avoid_within(&me, &v_if, sensed, horizon, self.sf, &self.p.bsoa);
                self.sf = o.sense;
                o.velocity
            }
            ObstacleLayer::Svf => {
                // Without a horizon only a non-finite distance fails, and sqrt keeps finiteness.
                let pts: Vec<Vec2> = sensed
                    .filter(|q| match horizon {
                        f64::INFINITY => (q - me).norm_squared() < horizon,
                        _ => (q - me).norm() < horizon,
                    })
                    .collect();
                let o = svf::avoid(&me, &v_if, &pts, self.follow, &self.p.svf);
                self.follow = o.follow;
                o.velocity
            }
        };
        let mut v = clamp_norm(v, self.v_max);
        if !(v.x.is_finite() && v.y.is_finite()) {
            v = Vec2::zeros();
        }
        self.last_vel = v;
        v
    }

    /// Step 2b's broadcast (and what 2c, 2d and 2e need of others): the status of this tick,
    /// to every robot within R_cm: position, detections above I_min, candidacy (with pb_i if
    /// kept) and the found targets.
    fn broadcast(
        &mut self,
        s: &Sense,
        signals: &[(usize, f64)],
        cand: Option<(u32, Role, Option<u32>)>,
        member: bool,
        out: &mut Outbox<Msg>,
    ) {
        let i_min = self.p.subgroup.i_min;
        let mut detections: Vec<(u32, f32)> = signals
            .iter()
            .filter(|(_, i)| *i > i_min)
            .map(|(t, i)| (*t as u32, *i as f32))
            .collect();
        detections.truncate(crate::section::MAX_SIGNALS);
        let status = Status {
            pos: pack(s.pos),
            detections,
            candidacy: cand.map(|(t, role, comm)| Candidacy {
                target: t,
                role: wire_role(role, comm),
                member,
                pb: if member {
                    self.memory
                        .and_then(|m| m.pb)
                        .map(|(q, f)| (pack([q.x, q.y]), f as f32))
                } else {
                    None
                },
            }),
            found: self.found_list(),
        };
        out.broadcast(Msg::Status(status.clone()));
        self.last_status = Some(status);
    }
}

impl Behaviour for Search {
    type Msg = Msg;

    /// One step of the loop of spec 2.9 (see the module doc); messages heard were sent at the
    /// previous tick.
    fn step_refs(&mut self, s: &Sense, inbox: &[&Received<Msg>], out: &mut Outbox<Msg>) -> Command {
        if let Mode::Declared { target } = self.mode {
            return self.declared_step(target, out, 0);
        }
        // 1. Arrival: this robot found a target at the last move.
        if let Some(t) = self.arrival(s) {
            return self.declared_step(t, out, EVENT_TARGET_DECLARED);
        }
        // 2. The radio: found targets and the statuses heard.
        let heard = self.listen(inbox);
        let me = Vec2::new(s.pos[0], s.pos[1]);
        // 3. Candidacy: Type I by own signals (eqs. 2-3), else Type II.
        let signals = self.own_signals(s);
        let cand = self.candidacy(&me, &signals, &heard);
        // 4. Closed-loop adjustment (Table 1).
        let kept = cand.filter(|&(t, role, _)| self.closed_loop_adjustment(t, role, &heard));
        let member = kept.is_some();
        // 5. Subgroup memory (pb_i, sgb).
        let bests = self.subgroup_memory(kept.map(|c| c.0), me, &signals, &heard);
        // 6. Cooperative velocity (eq. 11, ARBA) or roaming velocity (eq. 5).
        self.last_estimate = None;
        let (v_if, horizon) = match (kept, bests) {
            (Some((t, role, _)), Some(b)) => self.cooperative_velocity(s, me, (t, role), b, &heard),
            _ => (self.roaming_velocity(me, &heard), None),
        };
        // 7. Obstacle layer (BSOA or SVF).
        let v = self.obstacle_layer(s, me, v_if, horizon);
        // 8. Status broadcast.
        self.broadcast(s, &signals, cand, member, out);
        Command {
            cmd: [v.x, v.y],
            events: if member {
                STATE_COOPERATIVE
            } else {
                STATE_ROAMING
            },
            ..Command::default()
        }
    }
}

#[cfg(test)]
mod tests;
