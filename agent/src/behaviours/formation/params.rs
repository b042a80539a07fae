//! The formation behaviour's parameters: the kernels' [`FormationParams`] (controller, ORCA,
//! optimiser) and the behaviour's own choices, read from `formation.kernels`; the numbers the
//! scenario already holds elsewhere (box, radius, obstacles, V_p, epsilon) are derived from it,
//! so each has one source.

use super::relay::RelayParams;
use super::detour::DetourParams;
use super::escape::EscapeParams;
use crate::formation::blocked::BlockedParams;
use crate::formation::swaps::SwapParams;
use crate::formation::FormationParams;
use serde::{Deserialize, Serialize};
use swarm::scenario::{Check, ConfigError, Scenario};
use swarm::sections::formation::{FormationSection, Reassignment};

/// `formation.kernels`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Params {
    /// The kernels' numbers (agent/src/formation/params.rs documents each).
    #[serde(flatten)]
    pub kernels: FormationParams,
    /// The coordinator waits at most this many ticks to hear every live robot's start
    /// position before it solves with those it heard. [chosen] 20 (5 s at tau = 0.25); with
    /// no loss it hears everyone at tick 1.
    pub gather_ticks: u32,
    /// Decentralised swaps (`formation.kernels.swaps`): least gain, range, the handshake's
    /// timeout and settle ticks (agent/src/formation/swaps.rs documents each).
    pub swaps: SwapParams,
    /// Added to every radius in ORCA (robots, discs, lost robots): a safety margin for what
    /// lock-step ORCA does not model (neighbours sensed one step old, the LP's fallback in a
    /// crowd). [chosen] 0.05: without it 100 robots under swaps overlapped by up to 0.07.
    pub orca_margin: f64,
    /// A robot ORCA holds still beside a wreck, away from its slot, this many ticks in a row
    /// squeezes past the wrecks: they keep only their buffered cells (true radii) until it
    /// is 2 (r + orca_margin) and 1.5 steps clear of every wreck (squeeze.rs). [chosen] 10 (2.5 s at tau =
    /// 0.25): robots boxed in by exits of 4.14-4.17 between wrecks, passable at 2r = 2 from
    /// each but not at 2.1, stood still for thousands of ticks (docs/formation.md 9). 0: never.
    pub squeeze_after_ticks: u32,
    /// Backing out of a notch of wrecks (escape.rs, `formation.kernels.escape`): a robot
    /// still held still while it squeezes plans a path round the wrecks at the true radii.
    pub escape: EscapeParams,
    /// The re-plan after a robot is killed under `reassignment = "swaps"`
    /// (`formation.kernels.replan`).
    pub replan: ReplanParams,
    /// The relayed centralised mode (`formation.kernels.relay`, relay.rs): absent, the
    /// coordinator's plan goes out in one message to the robots in its radio range.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub relay: Option<RelayParams>,
    /// The wreck detour (detour.rs, `formation.kernels.detour`). None: off. Resolved only for
    /// `reassignment = "swaps"` (like `swaps.blocked`), so the other scenarios' resolved
    /// scenarios, and so their recordings, keep their bytes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub detour: Option<DetourParams>,
}

/// The swaps mode's re-plan when the swarm is short of the pattern's slots (a robot died) or
/// a wreck blocks a slot: an elected coordinator re-solves eq. (14) for the robots left with
/// the wrecks as obstacles (docs/formation.md 9, "A robot killed under swaps").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ReplanParams {
    /// alpha's range in the re-plan. [chosen] [1, 1.1]: in the literal reading of eq. (5)
    /// q = ((alpha - 1) + R(theta)) s + d is a similarity of scale |alpha - 1 + e^(i theta)|,
    /// so the pattern stays near the template's own size (the thick letters are drawn 2.2
    /// apart, at the separation bound: alpha = 1 exactly is infeasible) and the search stays
    /// small: on configs/formation-swaps-16.toml, kills 30:5, 40:10, 50:7, 0.13-1.1 s against
    /// 0.7-1.4 s for [1, 1.25] and 1.2-1.4 s for [0.5, 2] (node budget spent).
    pub alpha_range: [f64; 2],
    /// theta's range in the re-plan. [chosen] [-pi, pi].
    pub theta_range: [f64; 2],
    /// The optimiser's node budget in the re-plan (it reports the gap it proved).
    /// [chosen] 20 000.
    pub max_nodes: usize,
    /// Every robot repeats a re-planned pattern for this many ticks after it adopted it (the
    /// coordinator's broadcast reaches only its comm radius, and loss drops some).
    /// [chosen] 20.
    pub relay_ticks: u64,
    /// Large swarms (the full plan exceeds `radio.max_message_bytes`; compact.rs, gossip.rs):
    /// the coordinator solves at the latest `gather_ticks + ticks_per_hop * hops` ticks after
    /// the need began, hops = ceil(box diagonal / comm_radius), the network's diameter.
    /// [chosen] 4: at loss 0.3 a hop fails 0.3 per tick, but every robot re-sends its gossip
    /// every tick, so 4 ticks a hop miss with 0.3^4 = 0.008 per link.
    pub ticks_per_hop: u64,
    /// Large swarms: the operations the plan's optimiser may spend (params.rs
    /// `OptimiserParams::set_work_budget`: a cold n x n Hungarian solve counts n^3, a warm one
    /// n^2 per row it augments; the corner bound's node 6 n^3), nodes at most `max_nodes`.
    /// [chosen] 3e10: the polygon bound certifies the first plan within it at 100 robots
    /// (0.02 s) and at 500 (2.3 s; at 3e9 its arcs stayed open and 400 000 nodes left a gap of
    /// 3.4 %); the corner bound gets 5 000 nodes at 100 robots and 40 at 500 from it
    /// (docs/formation.md 9, "The alignment polygon").
    pub max_work: f64,
    /// Large swarms: the moves (robots whose point a wreck blocks) a compact plan's
    /// shift-and-drop tries first; when no placement needs so few it tries again with as many
    /// as one message carries (compact.rs `moves_that_fit`: 30 at 500 robots, 512 bytes, 12
    /// wrecks). [chosen] 12 (6 bytes each at 500 robots): fewer robots change slot.
    pub max_moves: usize,
    /// Large swarms: at most this many wrecks in a compact plan, the nearest the pattern
    /// first. [chosen] 12 (16 bytes each; with the 63-byte bitmap and 12 moves a 500-robot
    /// plan stays under 512 bytes).
    pub max_dead: usize,
    /// Large swarms: when a wreck blocks a kept slot, the old placement is translated by the
    /// least clear shift on rings this far apart (compact.rs `nearest_clear_shift`) before
    /// the budgeted optimiser is tried. [chosen] 0.25 (one V_p tau step of configs/
    /// formation-100.toml).
    pub shift_step: f64,
    /// ... and at most this far. [chosen] 6.0: three times the blocked distance 2 (r +
    /// orca_margin) = 2.1, room for a wreck between two rows of the thick letter.
    pub max_shift: f64,
}

impl Default for ReplanParams {
    fn default() -> Self {
        ReplanParams {
            alpha_range: [1.0, 1.1],
            theta_range: [-std::f64::consts::PI, std::f64::consts::PI],
            max_nodes: 20_000,
            relay_ticks: 20,
            ticks_per_hop: 4,
            max_work: 3e10,
            max_moves: 12,
            max_dead: 12,
            shift_step: 0.25,
            max_shift: 6.0,
        }
    }
}

impl Default for Params {
    fn default() -> Self {
        Params {
            kernels: FormationParams::default(),
            gather_ticks: 20,
            swaps: SwapParams::default(),
            orca_margin: 0.05,
            squeeze_after_ticks: 10,
            escape: EscapeParams::default(),
            replan: ReplanParams::default(),
            relay: None,
            detour: None,
        }
    }
}

/// The scenario's section (the default when it has none).
pub fn section(sc: &Scenario) -> FormationSection {
    sc.formation().cloned().unwrap_or_default()
}

/// The parameters with the derived numbers filled in from the scenario.
pub fn parse_params(sc: &Scenario) -> Result<Params, String> {
    let f = section(sc);
    let mut p: Params = toml::Value::Table(f.kernels.clone())
        .try_into()
        .map_err(|e: toml::de::Error| e.message().to_string())?;
    let k = &mut p.kernels;
    k.box_min = [0.0, 0.0];
    k.box_max = [sc.arena.width, sc.arena.height];
    k.robot_radius = sc.robot.radius;
    k.obstacle_centres = sc.arena.discs.iter().map(|d| d.centre).collect();
    // The optimiser's C2 takes one radius: the largest disc's (conservative for the others;
    // ORCA uses each disc's own radius).
    k.obstacle_radius = sc
        .arena
        .discs
        .iter()
        .map(|d| d.radius)
        .fold(sc.robot.radius, f64::max);
    // robot.v_max is per tick: V_p = v_max / tau.
    k.max_speed = sc.robot.v_max / k.time_step;
    k.epsilon = f.epsilon;
    // The blocked-robot swap acts only in the swaps mode: resolved (and so recorded) there
    // alone, so that the other scenarios' recordings keep their bytes.
    if f.reassignment == Reassignment::Swaps {
        p.swaps.blocked.get_or_insert_with(BlockedParams::default);
        p.detour.get_or_insert_with(DetourParams::default);
    }
    Ok(p)
}

/// Checks the behaviour's side of `[formation]`.
pub fn validate(sc: &Scenario, c: &Check) -> Result<(), ConfigError> {
    let p = parse_params(sc).map_err(|m| c.err("formation.kernels", m))?;
    let k = &p.kernels;
    c.range_f("formation.kernels.time_step", k.time_step, 0.0, 1e6, true)?;
    c.range_f("formation.kernels.time_horizon", k.time_horizon, 0.0, 1e6, true)?;
    c.range_f(
        "formation.kernels.obstacle_time_horizon",
        k.obstacle_time_horizon,
        0.0,
        1e6,
        true,
    )?;
    c.range_f("formation.kernels.k_a", k.k_a, 0.0, 1e6, true)?;
    c.range_f("formation.kernels.neighbour_dist", k.neighbour_dist, 0.0, 1e9, false)?;
    c.range_f("formation.kernels.separation_margin", k.separation_margin, 0.0, 1e6, false)?;
    c.range_f("formation.kernels.obstacle_margin", k.obstacle_margin, 0.0, 1e6, false)?;
    c.range_u(
        "formation.kernels.accel_polygon_sides",
        k.accel_polygon_sides as u64,
        3,
        1024,
    )?;
    if let Some(a) = k.max_accel {
        c.range_f("formation.kernels.max_accel", a, 0.0, 1e9, true)?;
    }
    c.range_f("formation.kernels.swaps.min_gain", p.swaps.min_gain, 0.0, 1e9, false)?;
    c.range_f("formation.kernels.swaps.range", p.swaps.range, 0.0, 1e9, true)?;
    c.range_u("formation.kernels.swaps.timeout_ticks", p.swaps.timeout_ticks, 1, 1_000_000)?;
    c.range_u("formation.kernels.swaps.settle_ticks", p.swaps.settle_ticks, 1, 1_000_000)?;
    if let Some(b) = &p.swaps.blocked {
        let key = |k: &str| format!("formation.kernels.swaps.blocked.{k}");
        c.range_u(&key("wait_ticks"), b.wait_ticks, 1, 1_000_000)?;
        c.range_f(&key("progress"), b.progress, 0.0, 1e6, true)?;
        c.range_f(&key("in_place"), b.in_place, 0.0, 1e6, true)?;
        c.range_f(&key("min_distance"), b.min_distance, b.in_place, 1e6, false)?;
        c.range_f(&key("corridor"), b.corridor, 0.0, 1e6, true)?;
        c.range_f(&key("max_price"), b.max_price, 0.0, 1e9, false)?;
        c.range_u(&key("hold_ticks"), b.hold_ticks, 0, 1_000_000)?;
        c.range_u(&key("max_swaps"), b.max_swaps as u64, 0, 1_000_000)?;
        c.range_f(&key("make_way_speed"), b.make_way_speed, 0.0, 1.0, false)?;
        c.range_f(&key("make_way_steps"), b.make_way_steps, 0.0, 1e6, false)?;
    }
    c.range_f("formation.kernels.orca_margin", p.orca_margin, 0.0, 1e6, false)?;
    c.range_u("formation.kernels.squeeze_after_ticks", p.squeeze_after_ticks as u64, 0, 1_000_000)?;
    let e = &p.escape;
    c.range_u("formation.kernels.escape.after_ticks", e.after_ticks as u64, 0, 1_000_000)?;
    c.range_f("formation.kernels.escape.window", e.window, 0.0, 1e4, true)?;
    // At most 1000 cells across, as the detour's.
    c.range_f("formation.kernels.escape.cell", e.cell, e.window / 500.0, e.window, false)?;
    c.range_f("formation.kernels.escape.cell_tolerance", e.cell_tolerance, 0.0, 1e6, false)?;
    if let Some(d) = &p.detour {
        c.range_f("formation.kernels.detour.window", d.window, 0.0, 1e4, true)?;
        // At most 1000 cells across (a search of a million cells at worst, every tick).
        c.range_f("formation.kernels.detour.cell", d.cell, d.window / 500.0, d.window, false)?;
    }
    let o = &k.optimiser;
    for (key, r) in [
        ("formation.kernels.optimiser.alpha_range", o.alpha_range),
        ("formation.kernels.optimiser.theta_range", o.theta_range),
        ("formation.kernels.replan.alpha_range", p.replan.alpha_range),
        ("formation.kernels.replan.theta_range", p.replan.theta_range),
    ] {
        if !(r[0].is_finite() && r[1].is_finite() && r[0] <= r[1]) {
            return Err(c.err(key, format!("= {r:?} must be finite [lo, hi] with lo <= hi")));
        }
    }
    c.range_u(
        "formation.kernels.optimiser.max_nodes",
        o.max_nodes as u64,
        1,
        100_000_000,
    )?;
    // The polygon bound's budget (its Hungarian solves and their operations): NaN or a
    // huge count left the first plan without a bound on its work.
    c.range_u(
        "formation.kernels.optimiser.max_solves",
        o.max_solves as u64,
        4,
        100_000_000,
    )?;
    c.range_f("formation.kernels.optimiser.max_work", o.max_work, 1.0, 1e18, false)?;
    c.range_u(
        "formation.kernels.replan.max_nodes",
        p.replan.max_nodes as u64,
        1,
        100_000_000,
    )?;
    c.range_u("formation.kernels.replan.ticks_per_hop", p.replan.ticks_per_hop, 0, 1_000_000)?;
    c.range_f("formation.kernels.replan.max_work", p.replan.max_work, 1.0, 1e18, false)?;
    c.range_u("formation.kernels.replan.max_moves", p.replan.max_moves as u64, 0, 1_000)?;
    c.range_u("formation.kernels.replan.max_dead", p.replan.max_dead as u64, 0, 1_000)?;
    c.range_f("formation.kernels.replan.shift_step", p.replan.shift_step, 0.0, 1e6, true)?;
    c.range_f("formation.kernels.replan.max_shift", p.replan.max_shift, 0.0, 1e6, false)?;
    Ok(())
}
