//! The search behaviour's parameters (`[search.kernels]` of the scenario) and the mode.
//!
//! Every section defaults to the paper's values (Table 4) or the spec's suggestions
//! (docs/search.md section 5); a key that is not a field is an error.

use crate::kernels::virtual_force;
use crate::search::{
    arba, bsoa, calibration, estimator, subgroup, svf, tpepso, Params as KernelParams,
};
use serde::{Deserialize, Serialize};
use swarm::scenario::Scenario;

/// Everything the `search` behaviour uses, deserialised from `search.kernels`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// Eq. (5) and the roaming rule (two nearest robots heard; spec 2.3-2.4).
    pub virtual_force: virtual_force::Params,
    /// Eq. (33) signal model and the eq. (6) calibration, measured offline by each robot
    /// (paper 3.2). m, q, noise_sigma and l_t must equal the scenario's `[search]` values:
    /// the calibration measures the environment the robot works in.
    pub calibration: calibration::Params,
    /// Eqs. (7)-(10): T_est from >= 3 detectors.
    pub estimator: estimator::Params,
    /// Eq. (11): TPEPSO (mode *T) / EPSO (mode *E, c3 term dropped).
    pub tpepso: tpepso::Params,
    /// ARBA, the bat-algorithm baseline (modes *A; spec 5 item 29): the search layer in place
    /// of eq. (11); every value is an assumption (search/arba.rs, listed commented in
    /// configs/search.toml).
    pub arba: arba::Params,
    /// BSOA, Table 2 and eqs. (12)-(22) (modes B*).
    pub bsoa: bsoa::Params,
    /// SVF obstacle following (modes S*; a reconstruction, spec 5 item 27).
    pub svf: svf::Params,
    /// Eqs. (2)-(3), Type II attachment within R_cm and the closed-loop adjustment (g_max).
    pub subgroup: subgroup::Params,
    /// Ticks during which a robot that found a target repeats its "found" broadcast before it
    /// falls silent for good (3: a lost message is repeated; everyone also gossips the set of
    /// found targets it knows in its status). [chosen] spec 5 item 8 (finder stops) and item 24.
    pub declare_ticks: u32,
    /// A robot keeps its pb_i and its sgb while its subgroup target stays the same, also across
    /// short drops to roaming (true), so a robot that flickers out of a subgroup because of
    /// signal noise does not forget what it learnt about a static target; they are reset when
    /// it joins another target's subgroup or the target is found. With false they are reset
    /// whenever it leaves the subgroup ("pb since it joined", paper 3.3, literally).
    /// [chosen] spec 5 item 10.
    pub keep_memory_across_gaps: bool,
    /// Fitness of pb_i for a Type II robot that senses nothing of the target: its measured
    /// I_ij, which is 0 beyond L_T (eq. 1), at its position when it joins. [chosen] spec 5
    /// item 10 ("keep pb_i at their position on joining").
    pub type2_initial_fitness: f64,
    /// A cooperative robot that senses its target passes to the obstacle layer only the
    /// obstacle points nearer than its own distance estimate G^{-1}(I_ij) (eq. 6) plus this
    /// margin (10 = l_2); points farther away lie beyond the target. Without it, BSOA / SVF turn
    /// a robot away from a target that lies within L_T of a wall or an obstacle behind it (the
    /// trigger of Table 2 looks L_B = 100 ahead), and such targets are never reached. The paper
    /// limits avoidance to obstacles within L_T for the same reason (paper 3.4, "to keep targets
    /// near obstacles detectable"); this narrows that range to the target's estimated
    /// distance. A negative value turns the horizon off. [chosen] spec 5 items 6 and 22.
    pub goal_horizon_margin: f64,
    /// Robot-robot collision avoidance inside a subgroup: the eq. (5) repulsion of the two
    /// nearest robots heard, with cut-off d_0 = this distance (20 = 2 l_1), is added to the
    /// eq. (11) velocity V_if before the obstacle layer; 0 turns it off. The paper describes no
    /// collision avoidance among subgroup members (C4 of eq. 26 is obstacle avoidance only);
    /// without it the members of a subgroup collapse onto one point (sgb) and, with EPSO, stop
    /// there for good as soon as sgb is more than L_0 from the target (PSO stagnation).
    /// Applied in every search layer alike. [chosen] spec 5 item 23.
    pub subgroup_separation: f64,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            virtual_force: virtual_force::Params::default(),
            calibration: calibration::Params::default(),
            estimator: estimator::Params::default(),
            tpepso: tpepso::Params::default(),
            arba: arba::Params::default(),
            bsoa: bsoa::Params::default(),
            svf: svf::Params::default(),
            subgroup: subgroup::Params::default(),
            declare_ticks: 3,
            keep_memory_across_gaps: true,
            type2_initial_fitness: 0.0,
            goal_horizon_margin: 10.0,
            subgroup_separation: 20.0,
        }
    }
}

/// Obstacle layer (first letter of the mode, Table 3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ObstacleLayer {
    /// B: boundary-scan obstacle avoidance.
    Bsoa,
    /// S: simplified virtual-force obstacle following.
    Svf,
}

/// Search layer (second letter of the mode, Table 3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SearchLayer {
    /// T: TPEPSO, eq. (11) with the position estimate.
    Tpepso,
    /// E: EPSO, eq. (11) with c3 = 0 (spec 5 item 28).
    Epso,
    /// A: ARBA, the adaptive robotic bat algorithm (spec 5 item 29; search/arba.rs).
    Arba,
}

/// Parses `search.mode`: BT, BE, BA, ST, SE or SA.
pub fn parse_mode(mode: &str) -> Result<(ObstacleLayer, SearchLayer), String> {
    let b = mode.as_bytes();
    if b.len() != 2 {
        return Err(format!(
            "search.mode = {mode:?} is unknown: allowed BT, BE, BA, ST, SE, SA"
        ));
    }
    let obstacle = match b[0] {
        b'B' => ObstacleLayer::Bsoa,
        b'S' => ObstacleLayer::Svf,
        _ => {
            return Err(format!(
                "search.mode = {mode:?}: the obstacle layer must be B (BSOA) or S (SVF)"
            ))
        }
    };
    let search = match b[1] {
        b'T' => SearchLayer::Tpepso,
        b'E' => SearchLayer::Epso,
        b'A' => SearchLayer::Arba,
        _ => {
            return Err(format!(
                "search.mode = {mode:?}: the search layer must be T (TPEPSO), E (EPSO) or A (ARBA)"
            ))
        }
    };
    Ok((obstacle, search))
}

/// Parses `search.kernels` into [`Params`] (unknown keys are errors).
pub fn parse_params(sc: &Scenario) -> Result<Params, String> {
    Params::deserialize(sc.search.kernels.clone()).map_err(|e| format!("search.kernels: {e}"))
}

/// An upper bound of the encoded size of one status message (bincode, varint integers):
/// position 8, up to MAX_SIGNALS detections of (target <= 5, f32 4), the candidacy <= 40, the found list
/// (length <= 5, each id <= 5), enum tags and lengths.
pub fn status_size_bound(targets: u32) -> usize {
    8 + 5 + 9 * swarm::sections::search::MAX_SIGNALS + 40 + 5 + 5 * targets as usize + 8
}

/// Checks the search behaviour's parameters and mode against the scenario.
pub fn validate_search(sc: &Scenario) -> Result<(), String> {
    parse_mode(&sc.search.mode)?;
    let p = parse_params(sc)?;
    let kernels = KernelParams {
        virtual_force: p.virtual_force.clone(),
        calibration: p.calibration.clone(),
        estimator: p.estimator.clone(),
        tpepso: p.tpepso.clone(),
        arba: p.arba.clone(),
        bsoa: p.bsoa.clone(),
        svf: p.svf.clone(),
        subgroup: p.subgroup.clone(),
    };
    kernels
        .check_consistency()
        .map_err(|e| format!("search.kernels: {e}"))?;
    p.arba.check().map_err(|e| format!("search.kernels: {e}"))?;
    // Every kernel's V_max equals tpepso.v_max (check_consistency), and that equals the robot's.
    let v = sc.robot.v_max;
    if p.tpepso.v_max != v {
        return Err(format!(
            "search.kernels: tpepso.v_max = {} differs from robot.v_max = {v} (V_max, Table 4)",
            p.tpepso.v_max
        ));
    }
    if p.bsoa.l_b > sc.robot.sensing_radius {
        return Err(format!(
            "search.kernels: bsoa.l_b = {} exceeds robot.sensing_radius = {} (L_B)",
            p.bsoa.l_b, sc.robot.sensing_radius
        ));
    }
    let s = &sc.search;
    let c = &p.calibration;
    for (key, mine, world) in [
        ("m", c.m, s.signal_m),
        ("q", c.q, s.signal_q),
        ("noise_sigma", c.noise_sigma, s.noise_sigma),
        ("l_t", c.l_t, s.l_t),
    ] {
        if mine != world {
            return Err(format!(
                "search.kernels: calibration.{key} = {mine} differs from the environment's value {world} \
                 (the offline calibration measures the real signal)"
            ));
        }
    }
    if c.n_distances < 2 || c.repeats < 1 || !(c.d_min > 0.0 && c.d_min < c.l_t) {
        return Err(
            "search.kernels: calibration needs n_distances >= 2, repeats >= 1, 0 < d_min < l_t"
                .into(),
        );
    }
    if p.subgroup.g_max < 1 {
        return Err("search.kernels: subgroup.g_max must be >= 1".into());
    }
    if p.estimator.min_detectors < 1 {
        return Err("search.kernels: estimator.min_detectors must be >= 1".into());
    }
    if sc.radio.max_messages_per_tick < 1 {
        return Err("radio.max_messages_per_tick must be >= 1 for the search behaviour".into());
    }
    let need = status_size_bound(s.targets);
    if (sc.radio.max_message_bytes as usize) < need {
        return Err(format!(
            "radio.max_message_bytes = {} is too small for the search behaviour's status message \
             with {} targets (needs up to {need} bytes)",
            sc.radio.max_message_bytes, s.targets
        ));
    }
    Ok(())
}
