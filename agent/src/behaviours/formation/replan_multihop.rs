//! The swaps re-plan in a multi-hop swarm whose full plan does not fit one message (100 and
//! 500 robots): the election and gathering by gossip (gossip.rs), the compact plan
//! (compact.rs), solved by a budgeted branch-and-bound. The triggers are replan.rs's.
//!
//! Per tick, a robot in a need (its own trigger, or a neighbour's gossip of its key) merges
//! the gossip heard, adds itself (its point once it is final: in no handshake), makes and
//! accepts no new swap, takes no vacancy, and, if it is the lowest id known (the candidate),
//! every live robot's final point is known (`settled` counts `alive`: `held` is exact) and
//! leaves the deficit of points vacant, or the timeout (`replan.ticks_per_hop`) passed,
//! solves; otherwise it broadcasts its gossip. Two
//! robots may solve for one key (each took itself for the lowest at the timeout): the lower
//! coordinator's plan wins ([`Formation::better`]) and every robot relays the plan it holds
//! for `relay_ticks`, and whenever it hears a robot on an older epoch, so it floods.
//!
//! The optimiser's positions are the kept points' old slots (the coordinator hears only its
//! neighbours' positions): the re-plan looks for the placement nearest the old pattern that
//! keeps every slot clear of the wrecks (C2), so the robots' self-assignment (keep your point)
//! stays near the optimum of eq. (14) for the robots at their slots.

use super::compact::{choose, dead_list, nearest_clear_shift, own_slot, plan_of};
use super::gossip::{Gathering, Need};
use super::messages::CompactPlan;
use super::replan::NO_PLACEMENT;
use super::shift_drop::{spare_points, Search, CLEARANCE_SLACK, SHIFTED_AND_DROPPED};
use super::{transform_of, Formation, Msg};
use crate::formation::constraints::PatternConstraints;
use crate::formation::optimise::optimise_in;
use swarm::geometry::Vec2;
use swarm::Outbox;

/// The gap a re-plan reports when it translated the old placement (no bound: not a
/// certificate of eq. 14's optimum).
pub const SHIFTED: f64 = -2.0;

impl Formation {
    /// The template point this robot holds in its plan.
    pub(super) fn held_point(&self) -> Option<u16> {
        let plan = self.plan.as_ref()?;
        plan.points.get(self.slot?).copied()
    }

    /// One tick of the multi-hop re-plan (see the module comment); the plan report on the
    /// tick it solved.
    pub(super) fn replan_multihop(
        &mut self,
        k: u64,
        alive: u32,
        needs: &[Need],
        out: &mut Outbox<Msg>,
    ) -> Option<[f64; 4]> {
        let epoch = self.plan.as_ref()?.epoch;
        let joined = needs.iter().any(|n| n.epoch == epoch && n.alive == alive);
        if !joined && !self.replan_needed(alive) {
            self.gathering = None;
            return None;
        }
        if !self.gathering.as_ref().is_some_and(|g| g.is_for(epoch, alive)) {
            let points = self.template.len();
            self.gathering = Some(Gathering::start(k, epoch, alive, self.robots, points));
        }
        let point = self.held_point().map(|p| p as usize);
        // Its point is final once it is in no handshake: while gathering no new swap or
        // vacancy changes it (gossip.rs).
        let final_point = !self.swap.as_ref().is_some_and(|a| a.is_busy());
        let g = self.gathering.as_mut().expect("started above");
        for n in needs {
            g.merge(n);
        }
        g.note(self.robot, point, final_point);
        if g.need.candidate == self.robot {
            let plan = self.plan.as_ref().expect("checked above");
            let deficit = plan.points.len().saturating_sub(alive as usize);
            // Every live robot's final point is known (so `held` is exact and the handshakes
            // in flight at the need's start have settled) and the deficit is vacant.
            let gathered = g.complete() && g.vacant(&plan.points) >= deficit;
            if gathered || k >= g.since + self.replan_timeout {
                let since = g.since;
                let known = g.need.known.count();
                let started = std::time::Instant::now();
                self.extend_template();
                let (compact, gap, nodes) = self.solve_compact(alive);
                let seconds = started.elapsed().as_secs_f64();
                let slot = own_slot(&compact, self.held_point());
                let extra = format!(
                    ", {} wrecks, {} moves, {known} of {alive} known, need since {since}, {} bytes",
                    compact.dead.len(),
                    compact.moves.len(),
                    super::compact::compact_len(&compact),
                );
                let report = self.adopt_solved(k, (plan_of(&compact), gap, nodes), seconds, "re-plans (swaps, compact)", extra);
                self.slot = slot;
                self.compact = Some(compact);
                self.gathering = None;
                return Some(report);
            }
        }
        out.broadcast(Msg::Need(g.need.clone()));
        None
    }

    /// The compact plan for `alive` robots from the gathered `held` set: (plan, gap, nodes).
    fn solve_compact(&self, alive: u32) -> (CompactPlan, f64, usize) {
        let old = self.plan.as_ref().expect("a re-plan replaces a plan");
        let held = &self.gathering.as_ref().expect("gathering").need.held;
        let r = &self.p.replan;
        let n = (alive as usize).min(old.points.len()).max(1);
        // Moves: `max_moves` first (the shift-and-drop below prefers fewer robots moved), then
        // as many as the message carries; never more than it carries.
        let first = r.max_moves.min(self.moves_fit);
        let wide = self.moves_fit;
        let (kept, moves) = choose(
            &old.points,
            &self.targets,
            held,
            &self.wrecks,
            self.blocked_within(),
            n,
            wide,
        );
        // Positions: the kept points' old slots.
        let slots: Vec<usize> = (0..old.points.len())
            .filter(|j| kept.contains(old.points[*j] as usize))
            .collect();
        let positions: Vec<Vec2> = slots.iter().map(|j| self.targets[*j]).collect();
        // Every known wreck, the nearest the old slots first: the pattern is placed round all
        // of them; the plan carries the first `max_dead` (the message's room). With a
        // placement no known wreck blocks a new slot, so one left out of the message cannot
        // fire the re-plan trigger again; cutting the list before placing (14 deaths against
        // 12) let the optimiser put a slot on a wreck left out.
        let dead = dead_list(&old.dead, &self.wrecks, &positions, usize::MAX);
        let carried = || dead.iter().take(r.max_dead).copied().collect::<Vec<[f64; 2]>>();
        let points: Vec<u16> = kept.iter().map(|p| p as u16).collect();
        let sub = self.sub_template(&points);
        let mut params = self.p.kernels.clone();
        params.obstacle_centres.extend(dead.iter().copied());
        // With the old slots as positions the old placement costs 0, the global minimum of
        // eq. (14) without the wrecks: it is kept when no wreck blocks a kept slot (the
        // re-plan trigger's test, replan.rs: so it does not fire again) and every kept slot
        // is in the box (C1). Its spacing is at least the old pattern's (a subset of its
        // points): the fixed epoch-0 C of configs/formation-100.toml is not checked against
        // C3's margin either (with that check every run of docs/formation.md 9 went to the
        // optimiser). Else the budgeted branch-and-bound places the pattern with the wrecks
        // in C2.
        let c = PatternConstraints::new(&params);
        let within = self.blocked_within();
        let unblocked = positions.iter().all(|q| {
            c.in_box(*q) && dead.iter().all(|w| (q - Vec2::new(w[0], w[1])).norm() >= within)
        });
        if unblocked {
            let plan = CompactPlan {
                epoch: old.epoch + 1,
                coordinator: self.robot,
                transform: old.transform,
                kept,
                moves,
                dead: carried(),
            };
            return (plan, 0.0, 0);
        }
        // Else the cheapest clear translation of the old placement (compact.rs): clear of the
        // arena's discs by a robot's ORCA radius, of the wrecks as above.
        let reach = self.p.kernels.robot_radius + self.p.orca_margin;
        let clear = |q: Vec2| {
            c.in_box(q)
                && self.discs.iter().all(|d| (q - d.position).norm() >= d.radius + reach)
                && dead.iter().all(|w| (q - Vec2::new(w[0], w[1])).norm() >= within)
        };
        if let Some(delta) = nearest_clear_shift(&positions, clear, r.shift_step, r.max_shift) {
            let t = old.transform;
            let plan = CompactPlan {
                epoch: old.epoch + 1,
                coordinator: self.robot,
                transform: [t[0], t[1] + delta.x, t[2] + delta.y, t[3]],
                kept,
                moves,
                dead: carried(),
            };
            return (plan, SHIFTED, 0);
        }
        // Else shift-and-drop (shift_drop.rs): a translation of the whole old pattern that
        // leaves enough points clear, the blocked ones dropped and their robots moved to the
        // vacancies.
        let mut all_wrecks: Vec<Vec2> = dead.iter().map(|w| Vec2::new(w[0], w[1])).collect();
        for w in &self.wrecks {
            super::wrecks::remember(&mut all_wrecks, *w);
        }
        // First with the slack (slots the robots can reach beside a wreck), then without
        // (measured: 100 robots seed 1, five kills at 100, the slack left no placement).
        let (c, all_wrecks) = (&c, &all_wrecks);
        let clear_by = |slack: f64| {
            move |q: Vec2| {
                c.in_box(q)
                    && self.discs.iter().all(|d| (q - d.position).norm() >= d.radius + reach)
                    && all_wrecks.iter().all(|w| (q - w).norm() >= within + slack)
            }
        };
        let search = Search {
            points: &old.points,
            targets: &self.targets,
            held,
            wrecks: all_wrecks,
            n,
            max_moves: first,
            step: r.shift_step,
            max_shift: r.max_shift,
            keep_near_moves: false,
        };
        let found = search
            .best(&clear_by(CLEARANCE_SLACK))
            .or_else(|| search.best(&clear_by(0.0)));
        // Else the same with the template's spare points (shift_drop.rs) as vacancies.
        let (with_spare, spare_targets) = self.with_spares(&old.points, old.transform);
        let spare_search = Search {
            points: &with_spare,
            targets: &spare_targets,
            keep_near_moves: true,
            ..search
        };
        let found = found.or_else(|| spare_search.best(&clear_by(CLEARANCE_SLACK)));
        // Else the same searches with every move the message carries (more than `max_moves`
        // robots on blocked slots: measured 11 of 12 used on a 500-robot schedule).
        let found = found.or_else(|| {
            if wide <= first {
                return None;
            }
            let search = Search {
                max_moves: wide,
                ..search
            };
            let spare_search = Search {
                max_moves: wide,
                ..spare_search
            };
            search
                .best(&clear_by(CLEARANCE_SLACK))
                .or_else(|| search.best(&clear_by(0.0)))
                .or_else(|| spare_search.best(&clear_by(CLEARANCE_SLACK)))
        });
        if let Some(s) = found {
            let t = old.transform;
            let plan = CompactPlan {
                epoch: old.epoch + 1,
                coordinator: self.robot,
                transform: [t[0], t[1] + s.delta.x, t[2] + s.delta.y, t[3]],
                kept: s.kept,
                moves: s.moves,
                dead: carried(),
            };
            return (plan, SHIFTED_AND_DROPPED, 0);
        }
        params.optimiser.set_work_budget(r.max_work, positions.len(), r.max_nodes);
        let (transform, gap, nodes) =
            match optimise_in(&positions, &sub, &params, r.alpha_range, r.theta_range) {
                Ok(s) => (
                    [s.transform.alpha, s.transform.d[0], s.transform.d[1], s.transform.theta],
                    s.gap,
                    s.nodes,
                ),
                Err(e) => {
                    eprintln!("formation: robot {} re-plan found no placement: {e}", self.robot);
                    (old.transform, NO_PLACEMENT, 0)
                }
            };
        (
            CompactPlan {
                epoch: old.epoch + 1,
                coordinator: self.robot,
                transform,
                kept,
                moves,
                dead: carried(),
            },
            gap,
            nodes,
        )
    }

    /// The old pattern's points and slots followed by the spare points (shift_drop.rs) under
    /// `transform` (the template extended by [`Formation::extend_template`]).
    fn with_spares(&self, points: &[u16], transform: [f64; 4]) -> (Vec<u16>, Vec<Vec2>) {
        let spares: Vec<u16> = (self.robots..self.template.len()).map(|j| j as u16).collect();
        let t = transform_of(transform);
        let reading = self.p.kernels.transform_reading;
        let mut all: Vec<u16> = points.to_vec();
        all.extend(spares.iter().filter(|j| !points.contains(j)));
        let targets = t.targets(reading, &self.sub_template(&all));
        (all, targets)
    }

    /// Adds the spare points behind the template's one per robot (once; every robot the
    /// same, from the template alone).
    fn extend_template(&mut self) {
        if self.template.len() == self.robots {
            let spares = spare_points(&self.template);
            self.template.extend(spares);
        }
    }

    /// Adopts a compact plan heard: this robot's slot from its template point (before the
    /// plan replaces the old one), or none (it takes the nearest in `adopt_for_swaps`).
    pub(super) fn install_compact(&mut self, c: CompactPlan) {
        if c.kept.iter().any(|p| p >= self.template.len()) {
            self.extend_template();
        }
        let slot = own_slot(&c, self.held_point());
        self.install(plan_of(&c));
        self.slot = slot.filter(|s| *s < self.targets.len());
        self.compact = Some(c);
    }
}
