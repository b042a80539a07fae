//! The search behaviour's parameters (`[search.kernels]` of the scenario) and the mode.
//!
//! Every section defaults to the paper's values (Table 4) or the spec's suggestions
//! (docs/search.md section 5); a key that is not a field is an error.

use crate::kernels::{
    arba, bsoa, calibration, estimator, subgroup, svf, tpepso, Params as KernelParams,
};
use crate::section::SearchScenario;
use agent::kernels::virtual_force;
use serde::{Deserialize, Serialize};
use swarm::scenario::{Check, ConfigError, Scenario};

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
    /// A robot keeps the sgb it knows while its subgroup target stays the same, also across
    /// short drops to roaming (true), so a robot that flickers out of a subgroup because of
    /// signal noise does not forget where its subgroup found the strongest signal of a static
    /// target; it is reset when the robot joins another target's subgroup or the target is
    /// found. With false it is reset at every join. pb_i is always "the best since the robot
    /// joined the subgroup" (paper 3.3): it is not a choice and has no parameter.
    /// [chosen] spec 5 item 10.
    pub keep_subgroup_best_across_gaps: bool,
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
    /// How a roaming robot treats the arena walls (the paper has no wall rule, spec 5 item 6).
    /// `none` (default): the walls are obstacles like any other, sensed as boundary points
    /// (`arena.walls_sensed`) and avoided by the mode's obstacle layer (BSOA / SVF), the
    /// paper's only rule for what a robot must not cross; it steers some roaming robots along
    /// the walls. `mirror`: each wall is also a robot's mirror image in eq. (5), one more
    /// candidate of "the two nearest robots", so a roaming robot within L_R of a wall is pushed
    /// off it as it is pushed off a robot within 2 L_R. `reflect`: the kept heading is
    /// reflected off a wall the robot is within L_R of and heading into. Both alternatives keep
    /// sparse roaming robots L_R = L_T from the walls, so targets near the north and east walls
    /// (inside the target region) go unsensed: at N = 20 they leave runs censored
    /// (docs/search.md 5 item 6, section 8). [chosen] spec 5 item 6.
    pub wall_rule: WallRule,
}

/// The roaming wall rule ([`Params::wall_rule`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum WallRule {
    /// Walls only as sensed obstacle points.
    None,
    /// Walls as mirror robots in eq. (5) while roaming.
    Mirror,
    /// The roaming heading reflected off a wall within L_R.
    Reflect,
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
            keep_subgroup_best_across_gaps: true,
            goal_horizon_margin: 10.0,
            subgroup_separation: 20.0,
            wall_rule: WallRule::None,
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

/// The kernel parameters that are physical constants of the scenario, each with its one
/// source: (path below `search.kernels`, the scenario key, its value). The kernels take these
/// from the scenario; a copy written in `search.kernels` must agree with its source.
fn derived(sc: &Scenario) -> [(&'static str, &'static str, f64); 10] {
    let (v, s) = (sc.robot.v_max, &sc.search());
    [
        ("virtual_force.v_max", "robot.v_max", v),
        ("tpepso.v_max", "robot.v_max", v),
        ("arba.v_max", "robot.v_max", v),
        ("bsoa.v_max", "robot.v_max", v),
        ("svf.v_max", "robot.v_max", v),
        ("calibration.m", "search.signal_m", s.signal_m),
        ("calibration.q", "search.signal_q", s.signal_q),
        (
            "calibration.noise_sigma",
            "search.noise_sigma",
            s.noise_sigma,
        ),
        ("calibration.l_t", "search.l_t", s.l_t),
        ("bsoa.l_t", "search.l_t", s.l_t),
    ]
}

/// `search.kernels` with every derived constant the file leaves out filled in from its source.
fn kernels_with_derived(sc: &Scenario) -> toml::Table {
    let mut t = sc.search().kernels.clone();
    for (path, _, value) in derived(sc) {
        if kernel_is_set(sc, path) {
            continue;
        }
        let (section, key) = path.split_once('.').expect("dotted path");
        let sub = t
            .entry(section)
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        if let toml::Value::Table(sub) = sub {
            sub.insert(key.to_string(), toml::Value::Float(value));
        }
    }
    t
}

/// Parses `search.kernels` into [`Params`] (unknown keys are errors), the derived constants
/// from their sources.
pub fn parse_params(sc: &Scenario) -> Result<Params, String> {
    Params::deserialize(kernels_with_derived(sc)).map_err(|e| format!("search.kernels: {e}"))
}

/// An upper bound of the encoded size of one status message (bincode, varint integers):
/// position 8, up to MAX_SIGNALS detections of (target <= 5, f32 4), the candidacy <= 40, the found list
/// (length <= 5, each id <= 5), enum tags and lengths.
pub fn status_size_bound(targets: u32) -> usize {
    8 + 5 + 9 * crate::section::MAX_SIGNALS + 40 + 5 + 5 * targets as usize + 8
}

/// The allowed range of one numeric key of `search.kernels` (path below it).
struct Range {
    key: &'static str,
    lo: f64,
    hi: f64,
    /// (lo, hi] rather than [lo, hi].
    lo_open: bool,
}

const fn r(key: &'static str, lo: f64, hi: f64, lo_open: bool) -> Range {
    Range {
        key,
        lo,
        hi,
        lo_open,
    }
}

/// Largest distance any kernel works with (the arena's own bound, `Scenario::validate`).
const DIST: f64 = 1e7;
/// Largest signal value (Q, thresholds).
const SIGNAL: f64 = 1e12;
/// Largest count of ticks a kernel waits or repeats.
const TICKS: f64 = 1e6;
const PI: f64 = std::f64::consts::PI;

/// Every float and integer of `search.kernels` with the range that makes sense for it (a unit
/// test checks that every numeric key of the defaults is listed). Cross-field rules (V_max,
/// L_B, L_T agree; d_min < L_T; f_min <= f_max; w_min <= w_max) are checked after.
const RANGES: &[Range] = &[
    r("virtual_force.c", 0.0, DIST, true),
    r("virtual_force.l1", 0.0, DIST, true),
    r("virtual_force.l_r", 0.0, DIST, true),
    r("virtual_force.l_b", 0.0, DIST, true),
    r("virtual_force.v_max", 0.0, 1e6, true),
    r("calibration.m", 0.0, SIGNAL, true),
    r("calibration.q", 0.0, SIGNAL, true),
    r("calibration.noise_sigma", 0.0, SIGNAL, false),
    r("calibration.l_t", 0.0, DIST, true),
    r("calibration.d_min", 0.0, DIST, true),
    // Each robot measures n_distances x repeats signals at start (paper 3.2): bounded so that
    // start-up stays within seconds.
    r("calibration.n_distances", 2.0, 10_000.0, false),
    r("calibration.repeats", 1.0, 10_000.0, false),
    r("estimator.min_detectors", 1.0, 4096.0, false),
    r("estimator.max_detectors", 0.0, 4096.0, false),
    r("estimator.n_starts", 0.0, 1000.0, false),
    r("estimator.initial_step", 0.0, DIST, true),
    r("estimator.max_iterations", 1.0, 100_000.0, false),
    r("estimator.tolerance", 0.0, 1e6, true),
    r("estimator.start_tolerance", 0.0, 1e6, true),
    r("estimator.restarts", 0.0, 100.0, false),
    // PSO weights (eq. 11): an inertia above 2 or coefficients above 10 only diverge (the
    // velocity is clamped to V_max anyway); alpha is a share.
    r("tpepso.w", 0.0, 2.0, false),
    r("tpepso.c1", 0.0, 10.0, false),
    r("tpepso.c2", 0.0, 10.0, false),
    r("tpepso.c3", 0.0, 10.0, false),
    r("tpepso.alpha", 0.0, 1.0, false),
    r("tpepso.v_max", 0.0, 1e6, true),
    r("arba.f_min", 0.0, 1e3, false),
    r("arba.f_max", 0.0, 1e3, false),
    r("arba.loudness_initial", 0.0, 1e3, true),
    r("arba.loudness_decay", 0.0, 1.0, false),
    r("arba.pulse_rate_initial", 0.0, 1.0, false),
    r("arba.pulse_rate_growth", 0.0, 1e3, false),
    r("arba.w_max", 0.0, 2.0, false),
    r("arba.w_min", 0.0, 2.0, false),
    r("arba.local_walk", 0.0, 1e3, false),
    r("arba.stall_ticks", 0.0, TICKS, false),
    r("arba.escape_ticks", 0.0, TICKS, false),
    r("arba.v_max", 0.0, 1e6, true),
    r("bsoa.v_max", 0.0, 1e6, true),
    r("bsoa.l_b", 0.0, DIST, true),
    r("bsoa.l_t", 0.0, DIST, true),
    r("bsoa.l_2", 0.0, DIST, true),
    r("bsoa.heading_tolerance", 0.0, PI, true),
    r("bsoa.corridor_half_width", 0.0, DIST, false),
    r("bsoa.c", 0.0, DIST, true),
    r("bsoa.l_1", 0.0, DIST, true),
    r("bsoa.boundary.sample_spacing", 0.0, 1e3, true),
    r("bsoa.boundary.gap_factor", 0.0, 1e3, true),
    r("bsoa.boundary.min_gap_angle", 0.0, PI, false),
    r("svf.v_max", 0.0, 1e6, true),
    r("svf.l_b", 0.0, DIST, true),
    r("svf.engage_distance", 0.0, DIST, false),
    r("svf.follow_distance", 0.0, DIST, false),
    r("svf.max_correction", 0.0, PI, false),
    r("svf.heading_tolerance", 0.0, PI, true),
    r("svf.corridor_half_width", 0.0, DIST, false),
    r("subgroup.i_min", 0.0, SIGNAL, false),
    r("subgroup.g_max", 1.0, 4096.0, false),
    r("subgroup.r_cm", 0.0, DIST, true),
    r("declare_ticks", 0.0, TICKS, false),
    // Negative turns the horizon off.
    r("goal_horizon_margin", -DIST, DIST, false),
    r("subgroup_separation", 0.0, DIST, false),
];

/// Every numeric leaf of `t` as (dotted path, value).
fn numeric_leaves(t: &toml::Table, prefix: &str, out: &mut Vec<(String, f64)>) {
    for (k, v) in t {
        let path = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            toml::Value::Table(sub) => numeric_leaves(sub, &path, out),
            toml::Value::Float(x) => out.push((path, *x)),
            toml::Value::Integer(i) => out.push((path, *i as f64)),
            _ => {}
        }
    }
}

/// Checks every number of `p` against [`RANGES`] (keys named `search.kernels.<path>`).
fn check_ranges(p: &Params, c: &Check) -> Result<(), ConfigError> {
    let table = toml::Table::try_from(p)
        .map_err(|e| c.err(KERNELS, format!("cannot be written back: {e}")))?;
    let mut leaves = Vec::new();
    numeric_leaves(&table, "", &mut leaves);
    for (path, v) in leaves {
        let key = format!("{KERNELS}.{path}");
        match RANGES.iter().find(|r| r.key == path) {
            Some(r) => c.range_f(&key, v, r.lo, r.hi, r.lo_open)?,
            None if !v.is_finite() => {
                return Err(c.err(&key, format!("= {v} must be a finite number")))
            }
            None => {}
        }
    }
    let rel = |key: &str, ok: bool, need: String| -> Result<(), ConfigError> {
        if ok {
            Ok(())
        } else {
            Err(c.err(&format!("{KERNELS}.{key}"), need))
        }
    };
    let cal = &p.calibration;
    rel(
        "calibration.d_min",
        cal.d_min < cal.l_t,
        format!(
            "= {} must be below calibration.l_t = {}",
            cal.d_min, cal.l_t
        ),
    )?;
    rel(
        "calibration.repeats",
        cal.n_distances * cal.repeats <= 1_000_000,
        format!(
            "= {} times calibration.n_distances = {} is over 1,000,000 measurements a robot makes at start",
            cal.repeats, cal.n_distances
        ),
    )?;
    let a = &p.arba;
    rel(
        "arba.f_max",
        a.f_max >= a.f_min,
        format!("= {} must be at least arba.f_min = {}", a.f_max, a.f_min),
    )?;
    rel(
        "arba.w_max",
        a.w_max >= a.w_min,
        format!("= {} must be at least arba.w_min = {}", a.w_max, a.w_min),
    )?;
    Ok(())
}

const KERNELS: &str = "search.kernels";

/// Whether the scenario's `search.kernels` table sets `path` (dotted, below it).
fn kernel_is_set(sc: &Scenario, path: &str) -> bool {
    let mut t = &sc.search().kernels;
    let mut parts = path.split('.').peekable();
    while let Some(k) = parts.next() {
        match (t.get(k), parts.peek()) {
            (Some(_), None) => return true,
            (Some(toml::Value::Table(sub)), Some(_)) => t = sub,
            _ => return false,
        }
    }
    false
}

/// Parses `search.kernels`, an error naming the key below it (`search.kernels.tpepso.w`).
fn parse_params_checked(sc: &Scenario, c: &Check) -> Result<Params, ConfigError> {
    serde_path_to_error::deserialize(kernels_with_derived(sc)).map_err(|e| {
        let path = e.path().to_string();
        let key = if path.is_empty() || path == "." {
            KERNELS.to_string()
        } else {
            format!("{KERNELS}.{path}")
        };
        c.err(&key, e.into_inner().to_string())
    })
}

/// Checks the search behaviour's section: the mode, every kernel parameter in its range, and
/// the kernels against the scenario (the mission's `[search]` values are checked before, by
/// the mission). Errors name the exact key.
pub fn validate(sc: &Scenario, c: &Check) -> Result<(), ConfigError> {
    parse_mode(&sc.search().mode).map_err(|m| c.err("search.mode", m))?;
    let p = parse_params_checked(sc, c)?;
    // A derived constant written in the file must agree with its one source.
    for (path, source, value) in derived(sc) {
        if !kernel_is_set(sc, path) {
            continue;
        }
        let mut t = &sc.search().kernels;
        let (section, key) = path.split_once('.').expect("dotted path");
        if let Some(toml::Value::Table(sub)) = t.get(section) {
            t = sub;
        }
        let written = t
            .get(key)
            .and_then(|x| x.as_float().or(x.as_integer().map(|i| i as f64)));
        if written != Some(value) {
            return Err(c.err(
                &format!("{KERNELS}.{path}"),
                format!(
                    "= {}: this kernel takes {source} = {value}; leave it out, or set it equal",
                    written.map_or("?".to_string(), |w| w.to_string())
                ),
            ));
        }
    }
    check_ranges(&p, c)?;
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
    kernels.check_consistency().map_err(|m| {
        // "<path> = <v> but <path0> = <v0>": the first path is the key that disagrees.
        let path = m.split(" = ").next().unwrap_or("");
        c.err(&format!("{KERNELS}.{path}"), format!("disagrees: {m}"))
    })?;
    p.arba
        .check()
        .map_err(|m| c.err(&format!("{KERNELS}.arba"), m))?;
    // A kernel value that must agree with a scenario value: the error names the kernel key if
    // the file sets it, else the scenario key (the kernel's value is then its code default,
    // and what the user changed is the scenario's).
    let disagree = |kernel: &str, mine: f64, key: &str, theirs: f64, why: &str| -> ConfigError {
        if kernel_is_set(sc, kernel) {
            c.err(
                &format!("{KERNELS}.{kernel}"),
                format!("= {mine} {why} {key} = {theirs}"),
            )
        } else {
            c.err(
                key,
                format!(
                    "= {theirs}: the search behaviour's {KERNELS}.{kernel} is {mine} (its default) \
                     and {why} it; set both"
                ),
            )
        }
    };
    if p.bsoa.l_b > sc.robot.sensing_radius {
        return Err(disagree(
            "bsoa.l_b",
            p.bsoa.l_b,
            "robot.sensing_radius",
            sc.robot.sensing_radius,
            "must not exceed (L_B)",
        ));
    }
    let s = &sc.search();
    let need = status_size_bound(s.targets);
    if (sc.radio.max_message_bytes as usize) < need {
        return Err(c.err(
            "radio.max_message_bytes",
            format!(
                "= {} is too small for the search behaviour's status message with {} targets \
                 (needs up to {need} bytes)",
                sc.radio.max_message_bytes, s.targets
            ),
        ));
    }
    Ok(())
}

/// [`validate`] with the error as text ("<key> <message>"), every key from one file.
pub fn validate_search(sc: &Scenario) -> Result<(), String> {
    validate(
        sc,
        &Check {
            key_source: &|_| "scenario".to_string(),
        },
    )
    .map_err(|e| format!("{} {}", e.key, e.message))
}

#[cfg(test)]
mod validation_tests {
    use super::*;

    fn check(sc: &Scenario) -> Result<(), ConfigError> {
        validate(
            sc,
            &Check {
                key_source: &|_| "t.toml".to_string(),
            },
        )
    }

    #[test]
    fn every_number_of_the_kernels_has_a_range() {
        let table = toml::Table::try_from(Params::default()).unwrap();
        let mut leaves = Vec::new();
        numeric_leaves(&table, "", &mut leaves);
        assert!(leaves.len() > 50, "{}", leaves.len());
        for (path, v) in &leaves {
            let r = RANGES
                .iter()
                .find(|r| r.key == path)
                .unwrap_or_else(|| panic!("search.kernels.{path} has no range"));
            // The default lies in it.
            assert!(
                v.is_finite() && *v <= r.hi && (*v > r.lo || (!r.lo_open && *v == r.lo)),
                "{path} = {v}"
            );
        }
        // And every listed range names a real key.
        for r in RANGES {
            assert!(leaves.iter().any(|(p, _)| p == r.key), "{}", r.key);
        }
    }

    fn refused(kernels: &str) -> ConfigError {
        let mut sc = Scenario::default();
        sc.search_mut().kernels = kernels.parse().unwrap();
        check(&sc).expect_err(kernels)
    }

    #[test]
    fn a_non_finite_or_out_of_range_kernel_value_names_its_key() {
        check(&Scenario::default()).unwrap();
        for (text, key) in [
            ("[tpepso]\nw = nan\n", "search.kernels.tpepso.w"),
            ("[tpepso]\nc3 = inf\n", "search.kernels.tpepso.c3"),
            ("[tpepso]\nalpha = -0.5\n", "search.kernels.tpepso.alpha"),
            (
                "[arba]\nloudness_decay = 1.5\n",
                "search.kernels.arba.loudness_decay",
            ),
            (
                "[arba]\nf_min = 0.5\nf_max = 0.2\n",
                "search.kernels.arba.f_max",
            ),
            (
                "[bsoa.boundary]\nsample_spacing = 0.0\n",
                "search.kernels.bsoa.boundary.sample_spacing",
            ),
            (
                "[estimator]\ntolerance = -1.0\n",
                "search.kernels.estimator.tolerance",
            ),
            (
                "[calibration]\nrepeats = 0\n",
                "search.kernels.calibration.repeats",
            ),
            ("[subgroup]\ng_max = 0\n", "search.kernels.subgroup.g_max"),
            (
                "goal_horizon_margin = -inf\n",
                "search.kernels.goal_horizon_margin",
            ),
            ("declare_ticks = 10000000\n", "search.kernels.declare_ticks"),
        ] {
            let e = refused(text);
            assert_eq!(e.key, key, "{text}: {e}");
            assert_eq!(e.source, "t.toml");
        }
    }

    #[test]
    fn deserialisation_errors_name_the_key_below_kernels() {
        let e = refused("[subgroup]\ng_max = -1\n");
        assert_eq!(e.key, "search.kernels.subgroup.g_max", "{e}");
        let e = refused("[tpepso]\nomega = 0.4\n");
        assert_eq!(e.key, "search.kernels.tpepso.omega", "{e}");
        assert!(e.message.contains("omega"), "{e}");
        let e = refused("[tpepso]\nw = \"fast\"\n");
        assert_eq!(e.key, "search.kernels.tpepso.w", "{e}");
    }

    #[test]
    fn mismatches_name_the_key_that_disagrees() {
        let e = refused("[svf]\nv_max = 5.0\n");
        assert_eq!(e.key, "search.kernels.svf.v_max", "{e}");
        let e = refused("[calibration]\nm = 0.2\n");
        assert_eq!(e.key, "search.kernels.calibration.m", "{e}");
        // One source: a scenario value changed alone reaches every kernel that uses it.
        let mut sc = Scenario::default();
        sc.search_mut().noise_sigma = 0.5;
        sc.robot.v_max = 6.0;
        check(&sc).unwrap();
        let p = parse_params(&sc).unwrap();
        assert_eq!(p.calibration.noise_sigma, 0.5);
        for v in [
            p.virtual_force.v_max,
            p.tpepso.v_max,
            p.arba.v_max,
            p.bsoa.v_max,
            p.svf.v_max,
        ] {
            assert_eq!(v, 6.0);
        }
        let mut sc = Scenario::default();
        sc.robot.sensing_radius = 50.0;
        assert_eq!(check(&sc).unwrap_err().key, "robot.sensing_radius");
    }
}
