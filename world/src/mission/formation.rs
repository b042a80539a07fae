//! The formation paper's mission (docs/formation.md 1.4-1.5, 4.6): the robots' slots as they
//! report them (Action `report`: [slot x, slot y, slot index, plan epoch]; the coordinator's
//! plan tick reports the optimiser's figures instead), "formed" (every live robot within
//! epsilon of its own, distinct slot of the same plan epoch), and the paper's measures: K, T,
//! L, reassignments, the least robot-robot and robot-obstacle clearances, overlapping pairs,
//! the optimiser's gap and time. The obstacles are the arena's discs; the world core keeps the
//! bodies out of them.

use super::{DisplayState, LegendEntry, Mark, Mission, MissionEntry, MissionError, RunFacts};
use crate::body::closest_pairs;
use serde::Serialize;
use swarm::frames::Sense;
use swarm::recording::Event;
use swarm::scenario::{Check, ConfigError, Scenario};
use swarm::sections::formation::{
    FormationSection, REPORT_GAP_INFEASIBLE, REPORT_NO_SLOT, REPORT_PLAN, REPORT_PLAN_SHAPE,
    REPORT_PLAN_SHIFT, STATE_COORDINATOR, STATE_IN_PLACE,
};

pub const ENTRY: MissionEntry = MissionEntry {
    name: "formation",
    progress_label: "robots in place",
    implied_by: &["formation"],
    sections: &["formation"],
    validate,
    new,
};

/// Most robots for which the per-tick distance to the slot (Fig. 9) is kept in the summary.
pub const MAX_ERROR_SERIES_ROBOTS: usize = 16;

fn section(sc: &Scenario) -> FormationSection {
    sc.formation().cloned().unwrap_or_default()
}

/// Checks the world's side of `[formation]`: the template fits the robots, epsilon is a
/// distance, the robots have bodies.
fn validate(sc: &Scenario, c: &Check) -> Result<(), ConfigError> {
    let f = section(sc);
    f.template_points(sc.run.robots as usize)
        .map_err(|m| c.err(f.template_key(), m))?;
    c.range_f("formation.epsilon", f.epsilon, 0.0, 1e6, true)?;
    c.range_u("formation.lost_after_ticks", f.lost_after_ticks as u64, 1, 1_000_000)?;
    for (i, v) in f.unoptimised_centre.iter().enumerate() {
        if !v.is_finite() {
            return Err(c.err(
                &format!("formation.unoptimised_centre[{i}]"),
                "must be finite".to_string(),
            ));
        }
    }
    Ok(())
}

fn new(sc: &Scenario) -> Result<Box<dyn Mission>, MissionError> {
    Ok(Box::new(FormationMission::new(sc)?))
}

impl FormationMission {
    pub fn new(sc: &Scenario) -> Result<FormationMission, MissionError> {
    let f = section(sc);
    let n = sc.run.robots as usize;
    let template = f
        .template_points(n)
        .map_err(|message| MissionError::Setup {
            key: f.template_key().into(),
            message,
        })?;
    let centroid = template.iter().fold([0.0, 0.0], |a, p| {
        [a[0] + p[0] / n as f64, a[1] + p[1] / n as f64]
    });
    let unoptimised = template
        .iter()
        .map(|p| {
            [
                p[0] - centroid[0] + f.unoptimised_centre[0],
                p[1] - centroid[1] + f.unoptimised_centre[1],
            ]
        })
        .collect();
    let tau = f
        .kernels
        .get("time_step")
        .and_then(|v| v.as_float())
        .unwrap_or(DEFAULT_TIME_STEP);
    Ok(FormationMission {
        radius: sc.robot.radius,
        discs: sc
            .arena
            .discs
            .iter()
            .map(|d| (d.centre, d.radius))
            .collect(),
        epsilon: f.epsilon,
        end_when_formed: f.end_when_formed,
        time_step: tau,
        unoptimised,
        slots: vec![None; n],
        poses: Vec::new(),
        alive: vec![true; n],
        in_place: 0,
        live: n as u32,
        formed_at: None,
        reassignments: 0,
        min_robot_clearance: f64::INFINITY,
        min_obstacle_clearance: f64::INFINITY,
        overlapping_pairs: 0,
        max_overlapping_pairs: 0,
        obstacle_overlaps: 0,
        plans: Vec::new(),
        error_series: (n <= MAX_ERROR_SERIES_ROBOTS).then(|| vec![Vec::new(); n]),
        tick: 0,
        recorded_progress: None,
    })
    }
}

/// tau when the kernels do not set it (agent::formation::FormationParams' default).
pub const DEFAULT_TIME_STEP: f64 = 0.25;

/// A robot's slot as it reports it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Slot {
    pub at: [f64; 2],
    pub index: u32,
    pub epoch: u32,
}

/// One pattern solution the coordinator reported.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PlanReport {
    pub tick: u64,
    pub robot: u32,
    /// Proven optimality gap (cost - lower bound, squared units); -1 when the optimiser found
    /// no feasible placement (`feasible` false).
    pub gap: f64,
    /// False: the optimiser found no placement of the pattern satisfying the box, obstacle and
    /// separation constraints (within its node budget); the plan fell back to
    /// `formation.transform`, and the summary says "NO FEASIBLE PATTERN".
    pub feasible: bool,
    /// Wall seconds the branch-and-bound took in the coordinator's process.
    pub seconds: f64,
    pub nodes: u64,
    /// The pattern's parameters of eq. (5) in the kernels' reading (reported on the next two
    /// ticks; None until they arrive): the scale parameter alpha, the translation d and the
    /// rotation theta (radians).
    pub alpha: Option<f64>,
    pub d: Option<[f64; 2]>,
    pub theta: Option<f64>,
    /// The plan's epoch (with the parameters).
    pub epoch: Option<u32>,
}

/// The formation scenario's measures (docs/formation.md 4.1, 4.6), summary `mission.formation`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct FormationMetrics {
    pub robots: u32,
    /// Live robots within epsilon of their slot at the end (the progress bar's count).
    pub robots_in_place: u32,
    pub formed: bool,
    /// K: iterations (ticks) until the formation was complete; None: never (censored).
    pub iterations: Option<u64>,
    /// T = K tau, simulated seconds.
    pub simulated_time: Option<f64>,
    /// L: the sum over robots of their path lengths.
    pub path_length: f64,
    /// Times a robot's reported slot index changed.
    pub reassignments: u64,
    /// Least centre distance minus 2r over every pair and tick.
    pub min_robot_clearance: f64,
    /// Least centre distance minus (r + r_o) over robots, discs and ticks.
    pub min_obstacle_clearance: f64,
    /// Overlapping robot pairs (closer than 2r), summed over ticks: must be 0.
    pub overlapping_pairs: u64,
    pub max_overlapping_pairs_at_one_tick: u32,
    /// Robot-disc overlaps, summed over ticks.
    pub obstacle_overlaps: u64,
    /// Each pattern solve (the first, and re-plans after a robot was lost).
    pub plans: Vec<PlanReport>,
    /// Some plan found no feasible pattern (a plan with `feasible` false).
    pub no_feasible_pattern: bool,
    /// The final slots, by robot (None: no slot reported).
    pub slots: Vec<Option<Slot>>,
    /// Fig. 9: each robot's distance to its slot at every tick (small swarms only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub distance_to_slot: Option<Vec<Vec<f64>>>,
}

pub struct FormationMission {
    radius: f64,
    discs: Vec<([f64; 2], f64)>,
    epsilon: f64,
    end_when_formed: bool,
    time_step: f64,
    /// The template at alpha = 1, theta = 0 around `unoptimised_centre` (Fig. 6).
    pub unoptimised: Vec<[f64; 2]>,
    slots: Vec<Option<Slot>>,
    poses: Vec<[f64; 2]>,
    alive: Vec<bool>,
    in_place: u32,
    live: u32,
    formed_at: Option<u64>,
    reassignments: u64,
    min_robot_clearance: f64,
    min_obstacle_clearance: f64,
    overlapping_pairs: u64,
    max_overlapping_pairs: u32,
    obstacle_overlaps: u64,
    plans: Vec<PlanReport>,
    error_series: Option<Vec<Vec<f64>>>,
    tick: u64,
    /// The progress last pushed as an `Event::Progress` (None: none yet).
    recorded_progress: Option<(u32, u32)>,
}

impl FormationMission {
    /// The formation mission of `world`, if it runs one.
    pub fn of(world: &crate::World) -> Option<&FormationMission> {
        world.mission.as_any().downcast_ref::<FormationMission>()
    }

    pub fn metrics_now(&self, facts: &RunFacts) -> FormationMetrics {
        FormationMetrics {
            robots: self.slots.len() as u32,
            robots_in_place: self.in_place,
            formed: self.formed_at.is_some(),
            iterations: self.formed_at.map(|k| k + 1),
            simulated_time: self.formed_at.map(|k| (k + 1) as f64 * self.time_step),
            path_length: facts.distance_travelled,
            reassignments: self.reassignments,
            min_robot_clearance: self.min_robot_clearance,
            min_obstacle_clearance: self.min_obstacle_clearance,
            overlapping_pairs: self.overlapping_pairs,
            max_overlapping_pairs_at_one_tick: self.max_overlapping_pairs,
            obstacle_overlaps: self.obstacle_overlaps,
            plans: self.plans.clone(),
            no_feasible_pattern: self.plans.iter().any(|p| !p.feasible),
            slots: self.slots.clone(),
            distance_to_slot: self.error_series.clone(),
        }
    }

    /// Whether every live robot is within epsilon of its own slot, all of one epoch and
    /// distinct; and how many are within epsilon of theirs.
    fn judge(&self) -> (bool, u32) {
        let mut in_place = 0;
        let mut all = self.live > 0;
        let mut epoch = None;
        let mut taken = std::collections::BTreeSet::new();
        for (i, p) in self.poses.iter().enumerate() {
            if !self.alive[i] {
                continue;
            }
            let Some(s) = self.slots[i] else {
                all = false;
                continue;
            };
            let d = ((p[0] - s.at[0]).powi(2) + (p[1] - s.at[1]).powi(2)).sqrt();
            if d <= self.epsilon {
                in_place += 1;
            } else {
                all = false;
            }
            if *epoch.get_or_insert(s.epoch) != s.epoch || !taken.insert(s.index) {
                all = false;
            }
        }
        // A dead robot on a slot of the live robots' plan leaves a hole in the pattern: it
        // is complete only once a re-plan for the robots left is adopted.
        let hole = self.slots.iter().zip(&self.alive).any(|(s, alive)| {
            !alive && s.is_some_and(|s| Some(s.epoch) == epoch)
        });
        (all && !hole, in_place)
    }
}

const SLOT: [u8; 3] = [0, 150, 60];
const UNOPTIMISED: [u8; 3] = [150, 60, 200];
const FINAL: [u8; 3] = [30, 30, 30];

fn slot_mark(at: [f64; 2], r: f64) -> Mark {
    Mark::Circle {
        at,
        radius: r,
        colour: SLOT,
    }
}
fn unoptimised_mark(at: [f64; 2], r: f64) -> Mark {
    Mark::Circle {
        at,
        radius: r,
        colour: UNOPTIMISED,
    }
}
fn final_mark(at: [f64; 2], r: f64) -> Mark {
    Mark::Circle {
        at,
        radius: r,
        colour: FINAL,
    }
}

const STATES: &[DisplayState] = &[
    DisplayState {
        state: 0,
        name: "moving",
        colour: [60, 90, 200],
    },
    DisplayState {
        state: STATE_IN_PLACE as u8,
        name: "in place",
        // Teal, not the slots' green: a robot and a slot are two things.
        colour: [20, 170, 170],
    },
    DisplayState {
        state: STATE_COORDINATOR as u8,
        name: "coordinator",
        colour: [230, 120, 0],
    },
];

impl Mission for FormationMission {
    fn name(&self) -> &'static str {
        "formation"
    }
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    fn sense(&mut self, _robot: u32, _pos: [f64; 2], _out: &mut Sense) {}
    fn observe(&mut self, robot: u32, report: [f64; 4]) {
        let Some(slot) = self.slots.get_mut(robot as usize) else {
            return;
        };
        if !report.iter().all(|v| v.is_finite()) {
            return;
        }
        if report[2] == REPORT_PLAN {
            self.plans.push(PlanReport {
                tick: self.tick,
                robot,
                gap: report[0],
                feasible: report[0] != REPORT_GAP_INFEASIBLE,
                seconds: report[1],
                nodes: report[3] as u64,
                alpha: None,
                d: None,
                theta: None,
                epoch: None,
            });
            return;
        }
        if report[2] == REPORT_PLAN_SHAPE || report[2] == REPORT_PLAN_SHIFT {
            // The robot's last plan: its parameters follow it on the next two ticks.
            if let Some(plan) = self.plans.iter_mut().rev().find(|p| p.robot == robot) {
                if report[2] == REPORT_PLAN_SHAPE {
                    plan.alpha = Some(report[0]);
                    plan.theta = Some(report[1]);
                } else {
                    plan.d = Some([report[0], report[1]]);
                }
                plan.epoch = Some(report[3] as u32);
            }
            return;
        }
        if report[2] == REPORT_NO_SLOT || report[2] < 0.0 {
            *slot = None;
            return;
        }
        let new = Slot {
            at: [report[0], report[1]],
            index: report[2] as u32,
            epoch: report[3] as u32,
        };
        if let Some(old) = *slot {
            self.reassignments += u64::from(old.index != new.index);
        }
        *slot = Some(new);
    }
    fn update(&mut self, tick: u64, poses: &[[f64; 3]], alive: &[bool], events: &mut Vec<Event>) {
        self.tick = tick + 1;
        self.poses = poses.iter().map(|p| [p[0], p[1]]).collect();
        self.alive = alive.to_vec();
        self.live = alive.iter().filter(|a| **a).count() as u32;
        let r = self.radius;
        let (closest, pairs) = closest_pairs(&self.poses, 2.0 * r);
        self.min_robot_clearance = self.min_robot_clearance.min(closest - 2.0 * r);
        self.overlapping_pairs += pairs as u64;
        self.max_overlapping_pairs = self.max_overlapping_pairs.max(pairs);
        for p in &self.poses {
            for (c, ro) in &self.discs {
                let d = ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2)).sqrt() - r - ro;
                self.min_obstacle_clearance = self.min_obstacle_clearance.min(d);
                self.obstacle_overlaps += u64::from(d < 0.0);
            }
        }
        if let Some(series) = &mut self.error_series {
            for (i, s) in series.iter_mut().enumerate() {
                let p = self.poses[i];
                s.push(self.slots[i].map_or(f64::NAN, |q| {
                    ((p[0] - q.at[0]).powi(2) + (p[1] - q.at[1]).powi(2)).sqrt()
                }));
            }
        }
        let (all, in_place) = self.judge();
        self.in_place = in_place;
        // The progress figure into the recording when it changes (the viewer's counter).
        if self.recorded_progress != Some((in_place, self.live)) {
            self.recorded_progress = Some((in_place, self.live));
            events.push(Event::Progress {
                done: in_place,
                total: self.live,
            });
        }
        if all && self.formed_at.is_none() {
            self.formed_at = Some(tick);
        }
        if !all && !self.end_when_formed {
            // A formation broken again after it was complete counts from its last completion.
            self.formed_at = None;
        }
    }
    fn progress(&self) -> (u32, u32) {
        (self.in_place, self.live)
    }
    fn complete(&self) -> bool {
        self.end_when_formed && self.formed_at.is_some()
    }
    fn end_reason(&self) -> &'static str {
        "the formation is complete"
    }
    fn metrics(&self, facts: &RunFacts) -> Option<serde_json::Value> {
        serde_json::to_value(self.metrics_now(facts)).ok()
    }
    fn display_states(&self) -> &'static [DisplayState] {
        STATES
    }
    fn layer(&self) -> Vec<Mark> {
        let r = self.radius.max(0.1);
        let mut marks: Vec<Mark> = self
            .unoptimised
            .iter()
            .map(|p| unoptimised_mark(*p, r))
            .collect();
        marks.extend(self.slots.iter().flatten().map(|s| slot_mark(s.at, r)));
        marks.extend(
            self.poses
                .iter()
                .zip(&self.alive)
                .map(|(p, a)| final_mark(*p, if *a { r } else { 0.5 * r })),
        );
        marks
    }
    fn legend(&self) -> Vec<LegendEntry> {
        vec![
            LegendEntry {
                mark: unoptimised_mark([0.0; 2], 1.0),
                label: "un-optimised pattern",
            },
            LegendEntry {
                mark: slot_mark([0.0; 2], 1.0),
                label: "slots (optimised pattern)",
            },
            LegendEntry {
                mark: final_mark([0.0; 2], 1.0),
                label: "final discs (small: lost robot)",
            },
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mission(n: u32) -> FormationMission {
        let mut sc = Scenario::default();
        sc.run.robots = n;
        sc.robot.radius = 1.0;
        sc.run.behaviour = "formation".into();
        let mut m = FormationMission::new(&sc).unwrap();
        m.discs = vec![([10.0, 0.0], 2.0)];
        m
    }

    #[test]
    fn a_robot_dead_on_a_slot_of_the_plan_leaves_a_hole_until_a_re_plan() {
        let mut m = mission(3);
        let poses = [[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [6.0, 0.0, 0.0]];
        for i in 0..3 {
            m.observe(i, [3.0 * i as f64, 0.0, i as f64, 1.0]);
        }
        // Robot 2 dies before it stands on its slot: the two left stand on theirs.
        m.update(0, &poses, &[true, true, false], &mut vec![]);
        assert_eq!(m.progress(), (2, 2));
        assert!(!m.complete(), "robot 2's slot of epoch 1 is a hole");
        // A re-plan (epoch 2) for the two left.
        m.observe(0, [0.0, 0.0, 0.0, 2.0]);
        m.observe(1, [3.0, 0.0, 1.0, 2.0]);
        m.update(1, &poses, &[true, true, false], &mut vec![]);
        assert!(m.complete());
    }

    #[test]
    fn the_progress_figure_is_recorded_as_an_event_each_time_it_changes() {
        let mut m = mission(2);
        let poses = [[0.0, 0.0, 0.0], [3.0, 0.0, 0.0]];
        let mut ev = Vec::new();
        m.update(0, &poses, &[true, true], &mut ev);
        assert_eq!(ev, vec![Event::Progress { done: 0, total: 2 }]);
        m.observe(0, [0.0, 0.0, 0.0, 1.0]);
        for (k, want) in [(1, Some((1, 2))), (2, None)] {
            let mut ev = Vec::new();
            m.update(k, &poses, &[true, true], &mut ev);
            let want: Vec<Event> = want
                .map(|(done, total)| Event::Progress { done, total })
                .into_iter()
                .collect();
            assert_eq!(ev, want, "tick {k}");
        }
        // Robot 0 dies on its slot: 0 of 1 live robot in place.
        let mut ev = Vec::new();
        m.update(3, &poses, &[false, true], &mut ev);
        assert_eq!(ev, vec![Event::Progress { done: 0, total: 1 }]);
    }

    #[test]
    fn formed_when_every_robot_is_within_epsilon_of_a_distinct_slot_of_one_epoch() {
        let mut m = mission(2);
        let poses = [[0.0, 0.0, 0.0], [3.0, 0.0, 0.0]];
        m.observe(0, [0.0, 0.04, 0.0, 1.0]);
        m.observe(1, [3.0, 0.0, 0.0, 1.0]);
        m.update(0, &poses, &[true, true], &mut vec![]);
        assert!(!m.complete(), "same slot index twice");
        assert_eq!(m.progress(), (2, 2));
        m.observe(1, [3.0, 0.0, 1.0, 2.0]);
        m.update(1, &poses, &[true, true], &mut vec![]);
        assert!(!m.complete(), "two epochs");
        m.observe(0, [0.0, 0.06, 0.0, 2.0]);
        m.update(2, &poses, &[true, true], &mut vec![]);
        assert!(!m.complete(), "0.06 > epsilon");
        assert_eq!(m.progress(), (1, 2));
        m.observe(0, [0.0, 0.05, 0.0, 2.0]);
        m.update(3, &poses, &[true, true], &mut vec![]);
        assert!(m.complete());
        let k = m.metrics_now(&RunFacts {
            ticks: 4,
            distance_travelled: 1.5,
        });
        assert_eq!(k.iterations, Some(4));
        assert_eq!(k.simulated_time, Some(1.0));
        assert_eq!(k.reassignments, 1);
        // Pair 3 apart, r = 1: clearance 1; disc at (10, 0) radius 2: 10 - 3 - 3 = 4.
        assert!((k.min_robot_clearance - 1.0).abs() < 1e-12);
        assert!((k.min_obstacle_clearance - 4.0).abs() < 1e-12);
        assert_eq!(k.overlapping_pairs, 0);
        // A dead robot does not count; a plan report keeps the slot.
        m.observe(1, [0.1, 0.2, REPORT_PLAN, 7.0]);
        assert_eq!(m.plans.len(), 1);
        assert_eq!(m.plans[0].nodes, 7);
        assert_eq!((m.plans[0].alpha, m.plans[0].d), (None, None));
        m.observe(1, [1.25, -0.5, REPORT_PLAN_SHAPE, 3.0]);
        m.observe(1, [4.0, 5.0, REPORT_PLAN_SHIFT, 3.0]);
        let p = m.plans[0];
        assert_eq!(
            (p.alpha, p.theta, p.d, p.epoch),
            (Some(1.25), Some(-0.5), Some([4.0, 5.0]), Some(3))
        );
        assert_eq!(m.slots[1].map(|s| s.index), Some(1), "parameter reports keep the slot");
        assert!(m.plans[0].feasible);
        // A plan that found no feasible pattern says so in the summary.
        m.observe(0, [REPORT_GAP_INFEASIBLE, 0.0, REPORT_PLAN, 0.0]);
        assert!(!m.plans[1].feasible);
        let facts = RunFacts {
            ticks: 4,
            distance_travelled: 1.5,
        };
        assert!(m.metrics_now(&facts).no_feasible_pattern);
        m.update(4, &[[0.0, 0.0, 0.0], [1.5, 0.0, 0.0]], &[true, false], &mut vec![]);
        assert_eq!(m.progress(), (1, 1));
        assert_eq!(m.overlapping_pairs, 1);
    }

    #[test]
    fn the_template_must_fit_the_robots() {
        let mut sc = Scenario::default();
        sc.run.robots = 9;
        sc.set_formation(Some(FormationSection {
            template: vec![[0.0, 0.0]; 3],
            ..Default::default()
        }));
        let c = Check {
            key_source: &|_| "t.toml".to_string(),
        };
        assert_eq!(validate(&sc, &c).unwrap_err().key, "formation.template");
        sc.formation_mut().as_mut().unwrap().template.clear();
        validate(&sc, &c).unwrap();
    }
}
