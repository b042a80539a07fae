//! One tick of the relayed centralised modes (relay.rs has the three flows): elect, gather,
//! adopt what the root floods; at the root, plan, re-plan and reassign.
//!
//! The root plans once its table holds a position newer than the last change of the live
//! count (Sense `alive_robots`, the world's) for `alive` robots, or at the timeout (then for
//! those it has). A dead robot sends nothing after its death, so its entry never becomes that
//! fresh: the robots missing from a complete table are exactly the dead. It re-plans with the
//! next epoch when the live count changes, when it took over from another coordinator (the
//! old one is silent: a new root is elected when its beacon's stamp is older than the
//! timeout), when it hears of a robot that is not a member, or when a wreck the plan was not
//! made around blocks a slot (at most once per timeout). Where the re-plan puts the pattern:
//! relay_place.rs. Per step, eq. (15) by the Hungarian method on the gathered positions, each
//! extrapolated over its age.

use super::compact::dead_list;
use super::relay_place::place;
use super::shift_drop::CLEARANCE_SLACK;
use super::gossip::Bitmap;
use super::relay::{chunks, estimate, member_index, Head, Relay, RelayParams, Sigma, Up};
use super::replan::NO_PLACEMENT;
use super::replan_multihop::SHIFTED;
use super::{transform_of, Formation, Msg, Plan};
use crate::formation::constraints::PatternConstraints;
use crate::formation::hungarian::assign_targets;
use crate::formation::optimise::{optimise_in, optimise_without_rotation};
use std::collections::BTreeMap;
use swarm::geometry::Vec2;
use swarm::sections::formation::{PatternChoice, Reassignment};
use swarm::{Outbox, Received};

/// A robot's state in the relayed mode.
#[derive(Debug, Clone)]
pub struct RelayState {
    pub relay: Relay,
    params: RelayParams,
    timeout: u64,
    head: Option<Head>,
    /// Tick the head was adopted, and last sent.
    head_at: u64,
    head_sent: u64,
    /// The newest chunk of sigma per first member, and the tick it arrived.
    chunks: BTreeMap<u16, (Sigma, u64)>,
    /// The assignment this robot's slot came from.
    seq: u32,
    /// The root's last sigma sent, and when.
    sent: Vec<u16>,
    sent_at: u64,
    /// When the root's sigma last changed, and how long it waits before the next change
    /// (`RelayParams::reassign_ticks_per_hop` x hops).
    changed_at: u64,
    reassign_period: u64,
    /// The live count and the tick it last changed.
    alive: u32,
    alive_since: u64,
    planned_at: Option<u64>,
}

impl RelayState {
    pub fn new(me: u32, params: RelayParams, diagonal: f64, comm_radius: f64) -> RelayState {
        let timeout = params.timeout(diagonal, comm_radius);
        let reassign_period = params.reassign_ticks_per_hop * params.hops(diagonal, comm_radius);
        RelayState {
            relay: Relay::new(me, timeout),
            params,
            timeout,
            head: None,
            head_at: 0,
            head_sent: 0,
            chunks: BTreeMap::new(),
            seq: 0,
            sent: Vec::new(),
            sent_at: 0,
            changed_at: 0,
            reassign_period,
            alive: 0,
            alive_since: 0,
            planned_at: None,
        }
    }
}

/// (epoch, lower coordinator first, seq): which of two chunks is newer.
fn chunk_key(s: &Sigma) -> (u32, std::cmp::Reverse<u32>, u32) {
    (s.epoch, std::cmp::Reverse(s.coordinator), s.seq)
}

/// The pattern a head describes (sigma comes in chunks: no slots here).
pub fn plan_of_head(h: &Head) -> Plan {
    Plan {
        epoch: h.epoch,
        coordinator: h.coordinator,
        transform: h.transform,
        points: h.kept.iter().map(|p| p as u16).collect(),
        members: h.members.iter().map(|m| m as u32).collect(),
        slots: Vec::new(),
        dead: h.dead.iter().map(|d| [d[0] as f64, d[1] as f64]).collect(),
    }
}

/// Adds template points (lowest index first) to `points` up to `n`, of `len`; ascending.
fn fill_points(points: &mut Vec<u16>, n: usize, len: usize) {
    for j in 0..len as u16 {
        if points.len() >= n {
            break;
        }
        if !points.contains(&j) {
            points.push(j);
        }
    }
    points.truncate(n);
    points.sort_unstable();
}

/// Two wreck positions closer than this are one wreck (a relayed one is rounded to f32).
const SAME_WRECK: f64 = 1e-3;

/// Adds `w` to `known` unless a wreck within [`SAME_WRECK`] is there already.
fn remember_near(known: &mut Vec<Vec2>, w: Vec2) {
    if !known.iter().any(|k| (k - w).norm() < SAME_WRECK) {
        known.push(w);
    }
}

fn bitmap_of(ids: impl Iterator<Item = usize>, n: usize) -> Bitmap {
    let mut b = Bitmap::with_len(n);
    for i in ids {
        b.insert(i);
    }
    b
}

impl Formation {
    /// Step 2 in the relayed mode; the plan report on the tick the root solved.
    pub(super) fn relay_step(
        &mut self,
        k: u64,
        me: Vec2,
        vel: Vec2,
        alive: u32,
        inbox: &[&Received<Msg>],
        out: &mut Outbox<Msg>,
    ) -> Option<[f64; 4]> {
        let mut st = self.relay.take().expect("the relayed mode has its state");
        if st.alive != alive {
            st.alive = alive;
            st.alive_since = k;
        }
        let mut beacons = Vec::new();
        let mut ups: Vec<&Up> = Vec::new();
        let mut heads: Vec<&Head> = Vec::new();
        let mut sigmas: Vec<&Sigma> = Vec::new();
        for r in inbox {
            match &r.msg {
                Msg::Up(u) => {
                    beacons.push((u.root, u.stamp as u64, u.hops));
                    ups.push(u);
                }
                Msg::Head(h) => heads.push(h),
                Msg::Sigma(s) => sigmas.push(s),
                _ => {}
            }
        }
        st.relay.elect(k, &beacons);
        for u in ups {
            st.relay.absorb(u);
            if u.root == st.relay.root && u.hops > st.relay.hops {
                for w in &u.wrecks {
                    remember_near(&mut self.wrecks, Vec2::new(w[0] as f64, w[1] as f64));
                }
            }
        }
        st.relay.note_self(k, me, vel);
        for h in heads {
            if self.better(&plan_of_head(h)) {
                self.install(plan_of_head(h));
                self.slot = None;
                st.head = Some(h.clone());
                st.head_at = k;
                st.seq = 0;
            }
        }
        for s in sigmas {
            let newer = st
                .chunks
                .get(&s.first)
                .is_none_or(|(held, _)| chunk_key(s) > chunk_key(held));
            if newer {
                st.chunks.insert(s.first, (s.clone(), k));
            }
        }
        let report = if st.relay.is_root() {
            self.relay_root(k, me, alive, &mut st)
        } else {
            None
        };
        self.slot_from_chunks(&mut st);
        let mut up = st.relay.up(k, st.params.entries_per_message);
        up.wrecks = self.unplanned_wrecks(k, st.params.wrecks_per_message);
        out.broadcast(Msg::Up(up));
        if let Some(h) = &st.head {
            let root = h.coordinator == self.robot;
            if k < st.head_at + st.params.repeat_ticks
                || self.heard_older
                || (root && k >= st.head_sent + st.params.refresh_ticks)
            {
                out.broadcast(Msg::Head(h.clone()));
                st.head_sent = k;
            }
        }
        for (s, at) in st.chunks.values() {
            if k < at + st.params.repeat_ticks {
                out.broadcast(Msg::Sigma(s.clone()));
            }
        }
        self.relay = Some(st);
        report
    }

    /// Up to `n` of the wrecks this robot knows that its plan was not made around, a
    /// different window of them every tick.
    fn unplanned_wrecks(&self, k: u64, n: usize) -> Vec<[f32; 2]> {
        let planned = |w: &Vec2| {
            self.plan
                .iter()
                .flat_map(|p| p.dead.iter())
                .any(|d| (Vec2::new(d[0], d[1]) - w).norm() < SAME_WRECK)
        };
        let news: Vec<&Vec2> = self.wrecks.iter().filter(|w| !planned(w)).collect();
        if news.is_empty() {
            return Vec::new();
        }
        let start = k as usize % news.len();
        (0..n.min(news.len()))
            .map(|i| news[(start + i) % news.len()])
            .map(|w| [w.x as f32, w.y as f32])
            .collect()
    }

    /// Whether a wreck this robot knows lies within a robot radius of `at` (two robots'
    /// centres are at least 2r apart, so it is the wreck of the robot estimated there).
    fn wreck_known_near(&self, at: Vec2) -> bool {
        let r = self.p.kernels.robot_radius;
        self.wrecks.iter().any(|w| (w - at).norm() < r)
    }

    /// `dead` less the estimates a known wreck has since replaced (an entry that is not
    /// itself a known wreck, with one within a robot radius); an entry that is a known wreck
    /// (a head's is rounded to f32) takes the wreck's own position.
    fn superseded_estimates_dropped(&self, dead: &[[f64; 2]]) -> Vec<[f64; 2]> {
        dead.iter()
            .filter_map(|d| {
                let at = Vec2::new(d[0], d[1]);
                match self.wrecks.iter().find(|w| (*w - at).norm() < SAME_WRECK) {
                    Some(w) => Some([w.x, w.y]),
                    None => (!self.wreck_known_near(at)).then_some(*d),
                }
            })
            .collect()
    }

    /// Whether a known wreck the plan was not made around blocks one of its slots.
    fn wreck_blocks_a_slot(&self) -> bool {
        let Some(plan) = &self.plan else { return false };
        let within = self.blocked_within();
        self.wrecks.iter().any(|w| {
            !plan.dead.iter().any(|d| (Vec2::new(d[0], d[1]) - w).norm() < SAME_WRECK)
                && self.targets.iter().any(|t| (t - w).norm() < within)
        })
    }

    /// This robot's slot from the newest chunk of its head's assignment that holds it.
    fn slot_from_chunks(&mut self, st: &mut RelayState) {
        let Some(h) = &st.head else { return };
        let Some(i) = member_index(&h.members, self.robot) else {
            return;
        };
        let chunk = st.chunks.values().map(|(s, _)| s).find(|s| {
            s.epoch == h.epoch
                && s.coordinator == h.coordinator
                && (s.first as usize..s.first as usize + s.slots.len()).contains(&i)
        });
        if let Some(s) = chunk {
            let slot = s.slots[i - s.first as usize] as usize;
            if (s.seq > st.seq || self.slot.is_none()) && slot < self.targets.len() {
                self.slot = Some(slot);
                st.seq = s.seq;
            }
        }
    }

    /// The root's tick: plan or re-plan when due, else reassign (per-step) or refresh.
    fn relay_root(&mut self, k: u64, me: Vec2, alive: u32, st: &mut RelayState) -> Option<[f64; 4]> {
        // Positions newer than the last change of root or of the live count (strictly: a
        // robot killed on the tick of the change may have sent its entry of that tick).
        let since = st.relay.root_since.max(st.alive_since) + 1;
        let mut fresh: Vec<u32> = st.relay.fresh_since(since).map(|e| e.id).collect();
        if !fresh.contains(&self.robot) {
            fresh.push(self.robot);
            fresh.sort_unstable();
        }
        let complete = fresh.len() >= alive as usize;
        let waited = k >= since + st.timeout + self.p.gather_ticks as u64
            && k >= st.relay.root_since + st.timeout;
        let may_plan = st.planned_at.is_none_or(|t| k >= t + st.timeout);
        let due = match &self.plan {
            None => true,
            Some(p) => {
                p.coordinator != self.robot
                    || p.members.len() != alive as usize
                    || fresh.iter().any(|m| !p.members.contains(m))
                    || self.wreck_blocks_a_slot()
            }
        };
        if due && may_plan && (complete || waited) {
            return Some(self.relay_plan(k, me, fresh, st));
        }
        let plan = self.plan.as_ref()?;
        if plan.coordinator != self.robot {
            return None;
        }
        // Eq. (15) on the gathered positions (per-step); one-shot keeps sigma.
        let mut sigma = st.sent.clone();
        if self.f.reassignment == Reassignment::PerStep {
            let positions = self.member_positions(k, me, &plan.members, &st.sent, &st.relay);
            let mut s = Vec::new();
            if assign_targets(&positions, &self.targets, &mut self.hungarian, &mut s).is_ok() {
                let fresh: Vec<u16> = s.iter().map(|j| *j as u16).collect();
                let due = k >= st.changed_at + st.reassign_period;
                if takes(&st.sent, &fresh, due, st.params.reassign_small) {
                    sigma = fresh;
                }
            }
        }
        let refresh = k >= st.sent_at + st.params.refresh_ticks;
        if sigma != st.sent || refresh {
            if sigma != st.sent {
                st.changed_at = k;
            }
            self.send_sigma(k, sigma, refresh, st);
        }
        None
    }

    /// The members' positions at tick k from the table (a member without an entry: its slot).
    fn member_positions(&self, k: u64, me: Vec2, members: &[u32], sigma: &[u16], relay: &Relay) -> Vec<Vec2> {
        let tau = self.tau();
        members
            .iter()
            .enumerate()
            .map(|(i, m)| {
                if *m == self.robot {
                    return me;
                }
                match relay.entry(*m) {
                    Some(e) => estimate(e, k, tau),
                    None => sigma
                        .get(i)
                        .and_then(|s| self.targets.get(*s as usize))
                        .copied()
                        .unwrap_or(me),
                }
            })
            .collect()
    }

    /// Installs sigma as the root's assignment of tick k and queues the chunks that changed
    /// (all of them when `all`).
    fn send_sigma(&mut self, k: u64, sigma: Vec<u16>, all: bool, st: &mut RelayState) {
        let plan = self.plan.as_mut().expect("the root holds its plan");
        let size = st.params.sigma_chunk;
        for c in chunks(plan.epoch, plan.coordinator, k as u32, &sigma, size) {
            let from = c.first as usize;
            let old = st.sent.get(from..(from + c.slots.len()).min(st.sent.len()));
            if all || old != Some(&c.slots[..]) {
                st.chunks.insert(c.first, (c, k));
            }
        }
        if let Some(i) = plan.members.iter().position(|m| *m == self.robot) {
            self.slot = sigma.get(i).map(|s| *s as usize).filter(|s| *s < self.targets.len());
        }
        plan.slots = sigma.clone();
        st.sent = sigma;
        st.sent_at = k;
        st.seq = k as u32;
    }

    /// The root's sigma of its held plan as far as it knows it (a take-over knows the
    /// chunks it relayed).
    fn known_sigma(&self, st: &RelayState) -> Vec<Option<u16>> {
        let Some(plan) = &self.plan else { return Vec::new() };
        if plan.coordinator == self.robot {
            return st.sent.iter().map(|s| Some(*s)).collect();
        }
        let mut sigma = vec![None; plan.members.len()];
        for (s, _) in st.chunks.values() {
            if s.epoch == plan.epoch && s.coordinator == plan.coordinator {
                for (j, slot) in s.slots.iter().enumerate() {
                    if let Some(x) = sigma.get_mut(s.first as usize + j) {
                        *x = Some(*slot);
                    }
                }
            }
        }
        sigma
    }

    /// Plans (or re-plans) for `members` at tick k; the plan report.
    fn relay_plan(&mut self, k: u64, me: Vec2, members: Vec<u32>, st: &mut RelayState) -> [f64; 4] {
        let started = std::time::Instant::now();
        let n = members.len().min(self.template.len());
        let members: Vec<u32> = members.into_iter().take(n).collect();
        let positions = self.member_positions(k, me, &members, &[], &st.relay);
        let tau = self.tau();
        let old_sigma = self.known_sigma(st);
        // The wrecks: the old plan's, the left members' last positions and those known.
        let mut prefer: Vec<u16> = Vec::new();
        let (mut dead, old_transform, epoch) = match &self.plan {
            None => (Vec::new(), None, 1),
            Some(old) => {
                let mut left_points = Vec::new();
                // A left member's last position advanced one step stands for its wreck until
                // the wreck itself is known (sensed or relayed: exact); then the wreck
                // replaces it, so one death is one obstacle, not two.
                let mut dead = self.superseded_estimates_dropped(&old.dead);
                for (i, m) in old.members.iter().enumerate() {
                    if members.contains(m) {
                        continue;
                    }
                    if let Some(e) = st.relay.entry(*m) {
                        let at = estimate(e, e.tick as u64 + 1, tau);
                        if !self.wreck_known_near(at) {
                            dead.push([at.x, at.y]);
                        }
                    }
                    if let Some(Some(s)) = old_sigma.get(i) {
                        left_points.extend(old.points.get(*s as usize));
                    }
                }
                prefer = old.points.iter().copied().filter(|p| !left_points.contains(p)).collect();
                (dead, Some(old.transform), old.epoch + 1)
            }
        };
        let reading = self.p.kernels.transform_reading;
        let mut params = self.p.kernels.clone();
        let max_work = self.p.replan.max_work;
        let whole = self.sub_template(&(0..self.template.len() as u16).collect::<Vec<_>>());
        // A re-plan: the old transform's points clear of the wrecks, else its least
        // translation with enough clear points (relay_place.rs), else the budgeted optimiser
        // on the preferred points; a first plan: the pattern choice, budgeted.
        let within = self.blocked_within();
        let (transform, points, gap, nodes) = match old_transform {
            Some(t) => {
                let all = transform_of(t).targets(reading, &whole);
                // Every known wreck, the nearest the pattern first: the root places the
                // pattern round all of them and judges `wreck_blocks_a_slot` against all of
                // them; only the head is cut to `max_dead` (a plan round fewer than the
                // known wrecks re-planned every timeout when a wreck left out blocked a slot).
                dead = dead_list(&dead, &self.wrecks, &all, usize::MAX);
                params.obstacle_centres.extend(dead.iter().copied());
                let c = PatternConstraints::new(&params);
                let reach = self.p.kernels.robot_radius + self.p.orca_margin;
                let clear_by = |slack: f64| {
                    let (c, dead, discs) = (&c, &dead, &self.discs);
                    move |q: Vec2| {
                        c.in_box(q)
                            && discs.iter().all(|d| (q - d.position).norm() >= d.radius + reach)
                            && dead
                                .iter()
                                .all(|w| (q - Vec2::new(w[0], w[1])).norm() >= within + slack)
                    }
                };
                let r = &self.p.replan;
                // Slots just clear of a wreck leave their robots short of them under ORCA
                // (shift_drop.rs CLEARANCE_SLACK): with the slack first, then without.
                let placed = place(&all, &prefer, n, clear_by(CLEARANCE_SLACK), r.shift_step, r.max_shift)
                    .or_else(|| place(&all, &prefer, n, clear_by(0.0), r.shift_step, r.max_shift));
                match placed {
                    Some((delta, points)) if delta == Vec2::zeros() => (t, points, 0.0, 0),
                    Some((delta, points)) => ([t[0], t[1] + delta.x, t[2] + delta.y, t[3]], points, SHIFTED, 0),
                    None => {
                        let mut points = prefer.clone();
                        fill_points(&mut points, n, self.template.len());
                        let sub = self.sub_template(&points);
                        params.optimiser.set_work_budget(max_work, n, r.max_nodes);
                        match optimise_in(&positions, &sub, &params, r.alpha_range, r.theta_range) {
                            Ok(s) => (
                                [s.transform.alpha, s.transform.d[0], s.transform.d[1], s.transform.theta],
                                points,
                                s.gap,
                                s.nodes,
                            ),
                            Err(_) => (t, points, NO_PLACEMENT, 0),
                        }
                    }
                }
            }
            None => {
                let mut points = Vec::new();
                fill_points(&mut points, n, self.template.len());
                let sub = self.sub_template(&points);
                let most = params.optimiser.max_nodes;
                params.optimiser.set_work_budget(max_work, n, most);
                let solved = match self.f.pattern {
                    PatternChoice::Optimise => {
                        let o = &params.optimiser;
                        optimise_in(&positions, &sub, &params, o.alpha_range, o.theta_range).ok()
                    }
                    PatternChoice::NoRotation => optimise_without_rotation(&positions, &sub, &params).ok(),
                    PatternChoice::Fixed => None,
                };
                match solved {
                    Some(s) => (
                        [s.transform.alpha, s.transform.d[0], s.transform.d[1], s.transform.theta],
                        points,
                        s.gap,
                        s.nodes,
                    ),
                    None if self.f.pattern == PatternChoice::Fixed => (self.f.transform, points, 0.0, 0),
                    None => (self.f.transform, points, NO_PLACEMENT, 0),
                }
            }
        };
        let sub = self.sub_template(&points);
        let targets = transform_of(transform).targets(reading, &sub);
        let mut sigma = Vec::new();
        if assign_targets(&positions, &targets, &mut self.hungarian, &mut sigma).is_err() {
            sigma = (0..n).collect();
        }
        let plan = Plan {
            epoch,
            coordinator: self.robot,
            transform,
            points: points.clone(),
            members: members.clone(),
            slots: sigma.iter().map(|s| *s as u16).collect(),
            dead: dead.clone(),
        };
        let seconds = started.elapsed().as_secs_f64();
        let fresh = members.len();
        // Eq. (1)'s objective of the plan on the gathered positions, beside its gap.
        let cost: f64 = sigma.iter().enumerate().map(|(i, &j)| (positions[i] - targets[j]).norm_squared()).sum();
        let extra = format!(
            ", relayed ({fresh} of {} gathered, {} wrecks), cost {cost:.1}",
            st.alive,
            dead.len()
        );
        let what = if old_transform.is_some() { "re-plans (relayed)" } else { "plans" };
        let report = self.adopt_solved(k, (plan, gap, nodes), seconds, what, extra);
        st.head = Some(Head {
            epoch,
            coordinator: self.robot,
            transform,
            kept: bitmap_of(points.iter().map(|p| *p as usize), self.template.len()),
            members: bitmap_of(members.iter().map(|m| *m as usize), self.robots),
            dead: dead.iter().take(st.params.max_dead).map(|d| [d[0] as f32, d[1] as f32]).collect(),
        });
        st.head_at = k;
        st.head_sent = k;
        st.planned_at = Some(k);
        st.changed_at = k;
        st.sent = Vec::new();
        let sigma: Vec<u16> = sigma.iter().map(|s| *s as u16).collect();
        self.send_sigma(k, sigma, true, st);
        report
    }
}

/// Whether the root takes the new assignment `fresh` over the one it sent: a change of at most
/// `small` slots at once, a larger one only when the reassignment period is `due`
/// (`RelayParams::reassign_ticks_per_hop`, `reassign_small`).
fn takes(sent: &[u16], fresh: &[u16], due: bool, small: usize) -> bool {
    let changed = fresh.iter().zip(sent).filter(|(a, b)| a != b).count();
    due || (fresh.len() == sent.len() && changed <= small)
}

#[cfg(test)]
mod tests {
    use super::takes;

    #[test]
    fn a_large_reassignment_waits_for_its_period_and_a_small_one_does_not() {
        let sent = [0u16, 1, 2, 3, 4, 5];
        let swap = [1u16, 0, 2, 3, 4, 5];
        let shuffle = [5u16, 4, 3, 2, 1, 0];
        assert!(takes(&sent, &swap, false, 4));
        assert!(!takes(&sent, &shuffle, false, 4));
        assert!(takes(&sent, &shuffle, true, 4));
        // With small = 0 every change waits; a sigma of another size is never "small".
        assert!(!takes(&sent, &swap, false, 0));
        assert!(!takes(&sent[..2], &swap, false, 4));
    }
}
