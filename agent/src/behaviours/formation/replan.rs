//! The swaps mode's re-plan after a robot is killed (issue 16: "A robot killed mid-run: the
//! pattern re-plans for the robots left", under the decentralised swaps as well).
//!
//! Swaps start from the fixed pattern with no coordinator. A re-plan is needed when
//! - the swarm is short of the plan's slots (Sense `alive_robots`, the world's live count, is
//!   below the plan's number of template points): a robot died; or
//! - a wreck this robot knows (sensed in its Sense frame, or heard in a `Wrecks` message)
//!   lies within 2 (r + orca_margin) of a slot and the plan was not made around it.
//!
//! Then the robots elect a coordinator over the radio: the lowest id among itself and the
//! robots heard since the need began (a dead robot sends nothing after its death, so it
//! cannot be elected or counted). The coordinator gathers the live robots' statuses (until
//! it heard `alive_robots - 1` others or `gather_ticks` passed), keeps `alive_robots` template
//! points (it drops first the slots no live robot holds, nearest a wreck first: the dead
//! robots' slots), re-solves eq. (14) by branch-and-bound for those robots with every known
//! wreck as one more obstacle centre (constraint C2, radius r_o as the discs, conservative),
//! and broadcasts the plan with epoch + 1. Every robot repeats a new plan for `relay_ticks`
//! and adopts a plan of a higher epoch (equal: of a lower coordinator); swaps resume on the
//! new slots (a new handshake state; proposals of another epoch are ignored).
//!
//! The re-plan's alpha is kept near 1 (`replan.alpha_range`, params.rs says why).
//!
//! Complete, with a robot dead: every live robot within epsilon of its own slot, all of one
//! epoch, no slot twice (the mission's rule); since the re-planned pattern has exactly one
//! slot per live robot, that is the re-planned pattern once all adopted it.

use super::{transform_of, Formation, Heard, Plan};
use crate::formation::hungarian::{assign_targets, Hungarian};
use crate::formation::optimise::optimise_in;
use crate::formation::swaps::SwapAgent;
use std::collections::BTreeMap;
use swarm::geometry::Vec2;

/// A member of a re-plan whose robot the coordinator did not hear: any robot left without a
/// slot takes the nearest such slot.
pub const UNKNOWN_MEMBER: u32 = u32::MAX;

/// The gap a re-plan reports when the optimiser found no feasible placement (a report must be
/// finite).
pub const NO_PLACEMENT: f64 = -1.0;

impl Formation {
    /// Whether the robot's plan must be re-made: the swarm is short of its slots, or a known
    /// wreck it was not made around blocks one of them.
    pub(super) fn replan_needed(&self, alive: u32) -> bool {
        let Some(plan) = &self.plan else { return false };
        if plan.points.len() > alive as usize {
            return true;
        }
        let within = self.blocked_within();
        self.wrecks.iter().any(|w| {
            !plan.dead.iter().any(|d| d[0] == w.x && d[1] == w.y)
                && self.targets.iter().any(|t| (t - w).norm() < within)
        })
    }

    /// A wreck closer than this to a slot leaves no room for a robot there.
    pub(super) fn blocked_within(&self) -> f64 {
        2.0 * (self.p.kernels.robot_radius + self.p.orca_margin)
    }

    /// One tick of the re-plan at tick `k`: tracks since when it is needed, and if this robot
    /// is the coordinator and has gathered, solves and adopts the new plan. Returns the plan
    /// report (gap, seconds, nodes) on the tick it solved.
    pub(super) fn replan_step(&mut self, k: u64, me: Vec2, alive: u32) -> Option<[f64; 4]> {
        if !self.replan_needed(alive) {
            self.need_since = None;
            return None;
        }
        // A further death restarts the gathering (its statuses before it are no proof of life).
        let since = match self.need_since {
            Some((since, a)) if a == alive => since,
            _ => {
                self.need_since = Some((k, alive));
                k
            }
        };
        let live: BTreeMap<u32, Heard> = self
            .heard
            .iter()
            .filter(|(_, h)| h.tick >= since)
            .map(|(i, h)| (*i, *h))
            .collect();
        if live.keys().next().is_some_and(|low| *low < self.robot) {
            return None;
        }
        let gathered = live.len() as u32 + 1 >= alive;
        if !gathered && k < since + self.p.gather_ticks as u64 {
            return None;
        }
        let started = std::time::Instant::now();
        let solved = self.solve_replan(k, me, alive, &live);
        let seconds = started.elapsed().as_secs_f64();
        let wrecks = format!(", {} wrecks", solved.0.dead.len());
        let report = self.adopt_solved(k, solved, seconds, "re-plans (swaps)", wrecks);
        self.need_since = None;
        Some(report)
    }

    /// The re-planned pattern for `alive` robots: (plan, gap, nodes).
    fn solve_replan(
        &self,
        k: u64,
        me: Vec2,
        alive: u32,
        live: &BTreeMap<u32, Heard>,
    ) -> (Plan, f64, usize) {
        let old = self.plan.as_ref().expect("a re-plan replaces a plan");
        let n = (alive as usize).min(old.points.len()).max(1);
        // Members: this robot and those heard since the need began; if too few were heard,
        // unknown members (a robot heard only before the need may be the dead one: seed 3,
        // kill 25:0 gave the dead robot 0 a slot and left robot 3 on its old slot index).
        let mut members: Vec<(u32, Vec2)> = live
            .iter()
            .map(|(i, h)| (*i, self.estimate(h, k)))
            .collect();
        members.push((self.robot, me));
        members.sort_by_key(|(i, _)| *i);
        members.truncate(n);
        // The slots the members hold now (their last status of the old epoch).
        let mut held = vec![false; old.points.len()];
        for (i, _) in &members {
            let slot = if *i == self.robot {
                self.slot.map(|s| s as i32)
            } else {
                self.heard
                    .get(i)
                    .filter(|h| h.epoch == old.epoch)
                    .map(|h| h.slot)
            };
            if let Some(s) = slot.filter(|s| *s >= 0 && (*s as usize) < held.len()) {
                held[s as usize] = true;
            }
        }
        // Drop the slots nobody holds first (the dead robots'), then held ones; nearest a
        // wreck first, then by index.
        let wreck_distance = |j: usize| {
            self.wrecks
                .iter()
                .map(|w| (self.targets[j] - w).norm())
                .fold(f64::INFINITY, f64::min)
        };
        let mut order: Vec<usize> = (0..old.points.len()).collect();
        order.sort_by(|a, b| {
            held[*a]
                .cmp(&held[*b])
                .then(wreck_distance(*a).total_cmp(&wreck_distance(*b)))
                .then(a.cmp(b))
        });
        let drop = old.points.len() - n;
        let mut keep: Vec<usize> = order[drop..].to_vec();
        keep.sort_unstable();
        let points: Vec<u16> = keep.iter().map(|j| old.points[*j]).collect();
        let mut dead = old.dead.clone();
        for w in &self.wrecks {
            if !dead.iter().any(|d| d[0] == w.x && d[1] == w.y) {
                dead.push([w.x, w.y]);
            }
        }
        // Unknown members (fewer robots heard than live): padded at the dropped slots.
        let mut ids: Vec<u32> = members.iter().map(|(i, _)| *i).collect();
        let mut positions: Vec<Vec2> = members.iter().map(|(_, p)| *p).collect();
        for j in order.iter().take(drop).chain(order.iter()).cycle() {
            if positions.len() >= n {
                break;
            }
            ids.push(UNKNOWN_MEMBER);
            positions.push(self.targets[*j]);
        }
        let sub = self.sub_template(&points);
        let mut params = self.p.kernels.clone();
        params.obstacle_centres.extend(dead.iter().copied());
        params.optimiser.max_nodes = self.p.replan.max_nodes;
        let r = &self.p.replan;
        let (transform, sigma, gap, nodes) =
            match optimise_in(&positions, &sub, &params, r.alpha_range, r.theta_range) {
                Ok(s) => (
                    [s.transform.alpha, s.transform.d[0], s.transform.d[1], s.transform.theta],
                    s.assignment,
                    s.gap,
                    s.nodes,
                ),
                Err(e) => {
                    // No feasible placement: the old transform on the kept points, assigned
                    // by Hungarian (the wrecks stay in `dead`, so this does not repeat).
                    eprintln!("formation: robot {} re-plan found no placement: {e}", self.robot);
                    let targets = transform_of(old.transform).targets(params.transform_reading, &sub);
                    let mut sigma = Vec::new();
                    let mut h = Hungarian::new();
                    if assign_targets(&positions, &targets, &mut h, &mut sigma).is_err() {
                        sigma = (0..positions.len()).collect();
                    }
                    (old.transform, sigma, NO_PLACEMENT, 0)
                }
            };
        (
            Plan {
                epoch: old.epoch + 1,
                coordinator: self.robot,
                transform,
                points,
                members: ids,
                slots: sigma.iter().map(|s| *s as u16).collect(),
                dead,
            },
            gap,
            nodes,
        )
    }

    /// After a new plan was adopted: a fresh handshake state on this robot's slot of it (a
    /// robot the coordinator did not know takes the nearest slot of an unknown member, or of
    /// none).
    pub(super) fn adopt_for_swaps(&mut self, k: u64, me: Vec2) {
        let Some(plan) = &self.plan else { return };
        if self.swap_epoch == Some(plan.epoch) {
            return;
        }
        let slot = self.slot.or_else(|| {
            let mut free: Vec<bool> = vec![true; self.targets.len()];
            for (m, s) in plan.members.iter().zip(&plan.slots) {
                if *m != UNKNOWN_MEMBER {
                    if let Some(f) = free.get_mut(*s as usize) {
                        *f = false;
                    }
                }
            }
            (0..self.targets.len())
                .filter(|j| free[*j])
                .min_by(|a, b| {
                    (self.targets[*a] - me)
                        .norm()
                        .total_cmp(&(self.targets[*b] - me).norm())
                })
        });
        // No slot left for it: it keeps none (and so the formation cannot complete) rather
        // than an index of the old pattern.
        let Some(slot) = slot else {
            self.slot = None;
            self.swap = None;
            return;
        };
        self.slot = Some(slot);
        self.swap = Some(SwapAgent::new(self.robot as usize, slot));
        self.swap_epoch = Some(plan.epoch);
        self.adopted_at = k;
    }
}
