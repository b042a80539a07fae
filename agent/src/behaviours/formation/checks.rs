//! Load-time checks of `[formation]` and `[formation.kernels]` that a new user's file meets
//! before anything starts (docs/formation.md 9, "Unseen inputs (9 robots)"), beyond the ranges
//! of params.rs:
//!
//! - a key under `formation.kernels` the behaviour does not read (a typo) is refused, naming
//!   it and listing the keys allowed at that level (the kernels' table is flattened from
//!   several structs, so serde cannot refuse unknown keys there itself);
//! - a value of the wrong type names its own key path (serde's error on the flattened table
//!   names none);
//! - a key the scenario derives (box, radius, obstacles, V_p, epsilon) may only hold the
//!   derived value (as a resolved scenario.toml does): another value would be overwritten;
//! - ranges params.rs leaves open (cell_slack, the optimiser's gaps, gather_ticks, ...);
//! - `formation.transform` and `formation.template` finite;
//! - a template whose closest points stay closer than the separation 2r + separation_margin
//!   at the largest scale alpha_range reaches (no alpha is feasible), or whose widest pair
//!   does not fit the box at the least scale that separates them, is refused; a template
//!   closer than 2r at alpha = 1 that a larger alpha separates is accepted (the optimiser
//!   scales it: that is what alpha is for);
//! - `pattern = "fixed"`: its slots are known now, so slots closer than 2r, outside the box
//!   (less than r from a wall) or inside a disc are refused.
//!
//! What only the optimiser can decide (obstacles that leave no room for the pattern) is
//! reported at run time: the coordinator's plan report carries [`NO_PLAN_GAP`] and the run's
//! summary says "NO FEASIBLE PATTERN".

use super::params::{self, Params};
use crate::formation::blocked::BlockedParams;
use crate::formation::params::TransformReading;
use crate::formation::{Template, Transform};
use swarm::scenario::{Check, ConfigError, Scenario};
use swarm::sections::formation::{FormationSection, PatternChoice, REPORT_GAP_INFEASIBLE};

const KERNELS: &str = "formation.kernels";

/// The gap a plan reports when the pattern was not optimised: 0 for `pattern = "fixed"`,
/// [`REPORT_GAP_INFEASIBLE`] when the optimiser found no feasible placement (the plan then
/// falls back to `formation.transform`).
pub fn no_plan_gap(pattern: PatternChoice) -> f64 {
    if pattern == PatternChoice::Fixed {
        0.0
    } else {
        REPORT_GAP_INFEASIBLE
    }
}

/// What the agent's plan line adds to a plan's gap: the plain words when it is
/// [`REPORT_GAP_INFEASIBLE`]. A re-plan (`replan`: an old pattern existed) with no placement
/// keeps the previous pattern, not `formation.transform`.
pub fn gap_note(gap: f64, replan: bool) -> &'static str {
    match (gap == REPORT_GAP_INFEASIBLE, replan) {
        (false, _) => "",
        (true, false) => {
            " (NO FEASIBLE PATTERN: the optimiser found no placement; fallback formation.transform)"
        }
        (true, true) => " (no placement for the re-plan: the previous pattern kept)",
    }
}

/// Every check of this file, in the order a user meets them.
pub fn validate(sc: &Scenario, c: &Check) -> Result<(), ConfigError> {
    let f = params::section(sc);
    let allowed = allowed();
    unknown_keys(&f.kernels, &allowed, KERNELS, c)?;
    wrong_types(&f.kernels, &allowed, &mut Vec::new(), &allowed, c)?;
    let p = params::parse_params(sc).map_err(|m| c.err(KERNELS, m))?;
    derived(&f, &p, c)?;
    ranges(&p, c)?;
    finite(&f, c)?;
    template(sc, &f, &p, c)
}

/// The keys `formation.kernels` may hold: every parameter at its default (the optional
/// tables' too: the blocked swap's and the detour's, which only the swaps mode resolves, and
/// the relayed mode's, present only when the scenario asks for it).
fn allowed() -> toml::Table {
    let mut p = Params::default();
    p.swaps.blocked.get_or_insert_with(BlockedParams::default);
    p.detour.get_or_insert_with(Default::default);
    p.relay.get_or_insert_with(Default::default);
    toml::Table::try_from(&p).expect("the formation parameters serialise")
}

fn unknown_keys(
    user: &toml::Table,
    allowed: &toml::Table,
    path: &str,
    c: &Check,
) -> Result<(), ConfigError> {
    for (k, v) in user {
        let key = format!("{path}.{k}");
        match allowed.get(k) {
            None => {
                let names: Vec<&str> = allowed.keys().map(String::as_str).collect();
                return Err(c.err(
                    &key,
                    format!(
                        "is not a key of `{path}` (a typo is refused, not ignored): allowed keys: {}",
                        names.join(", ")
                    ),
                ));
            }
            Some(toml::Value::Table(a)) => {
                if let toml::Value::Table(u) = v {
                    unknown_keys(u, a, &key, c)?;
                }
            }
            Some(_) => {}
        }
    }
    Ok(())
}

/// Each value the user wrote, tried alone in the defaults: the first that does not
/// deserialise names its key path, serde's reason and the default's value.
fn wrong_types(
    user: &toml::Table,
    allowed: &toml::Table,
    path: &mut Vec<String>,
    root: &toml::Table,
    c: &Check,
) -> Result<(), ConfigError> {
    for (k, v) in user {
        path.push(k.clone());
        match (v, allowed.get(k)) {
            (toml::Value::Table(u), Some(toml::Value::Table(a))) => {
                wrong_types(u, a, path, root, c)?;
            }
            (_, default) => {
                let mut trial = root.clone();
                set(&mut trial, path, v.clone());
                if let Err(e) = toml::Value::Table(trial).try_into::<Params>() {
                    let shown = default.map_or(String::new(), |d| format!(" (default: {d})"));
                    return Err(c.err(
                        &format!("{KERNELS}.{}", path.join(".")),
                        format!("= {v} has the wrong type: {}{shown}", e.message()),
                    ));
                }
            }
        }
        path.pop();
    }
    Ok(())
}

fn set(t: &mut toml::Table, path: &[String], v: toml::Value) {
    let (last, head) = path.split_last().expect("a key path");
    let mut at = t;
    for k in head {
        at = match at
            .entry(k.clone())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
        {
            toml::Value::Table(inner) => inner,
            _ => return,
        };
    }
    at.insert(last.clone(), v);
}

/// The numbers of a TOML value (a number or nested arrays of numbers), flattened.
fn numbers(v: &toml::Value, out: &mut Vec<f64>) -> bool {
    match v {
        toml::Value::Float(x) => out.push(*x),
        toml::Value::Integer(i) => out.push(*i as f64),
        toml::Value::Array(a) => return a.iter().all(|x| numbers(x, out)),
        _ => return false,
    }
    true
}

/// Kernel keys whose value the scenario derives: allowed only at the derived value.
fn derived(f: &FormationSection, p: &Params, c: &Check) -> Result<(), ConfigError> {
    let k = &p.kernels;
    let centres: Vec<f64> = k.obstacle_centres.iter().flatten().copied().collect();
    let derived: [(&str, Vec<f64>, &str); 7] = [
        ("box_min", k.box_min.to_vec(), "the arena's corner (0, 0)"),
        ("box_max", k.box_max.to_vec(), "[arena.width, arena.height]"),
        ("robot_radius", vec![k.robot_radius], "robot.radius"),
        (
            "obstacle_radius",
            vec![k.obstacle_radius],
            "the largest arena.discs radius (at least robot.radius)",
        ),
        ("obstacle_centres", centres, "the arena.discs centres"),
        ("max_speed", vec![k.max_speed], "robot.v_max / formation.kernels.time_step"),
        ("epsilon", vec![k.epsilon], "formation.epsilon"),
    ];
    for (key, value, from) in derived {
        let Some(given) = f.kernels.get(key) else {
            continue;
        };
        let mut got = Vec::new();
        let same = numbers(given, &mut got)
            && got.len() == value.len()
            && got
                .iter()
                .zip(&value)
                .all(|(a, b)| (a - b).abs() <= 1e-9 * b.abs().max(1.0));
        if !same {
            return Err(c.err(
                &format!("{KERNELS}.{key}"),
                format!(
                    "= {given} is derived from {from} (= {value:?} in this scenario) and would be \
                     overwritten: set {from} instead, or leave the key out"
                ),
            ));
        }
    }
    Ok(())
}

/// The ranges params.rs does not check.
fn ranges(p: &Params, c: &Check) -> Result<(), ConfigError> {
    let key = |k: &str| format!("{KERNELS}.{k}");
    let k = &p.kernels;
    c.range_f(&key("cell_slack"), k.cell_slack, 0.0, 1e6, false)?;
    c.range_f(&key("optimiser.gap_abs"), k.optimiser.gap_abs, 0.0, 1e18, false)?;
    c.range_f(&key("optimiser.gap_rel"), k.optimiser.gap_rel, 0.0, 1.0, false)?;
    c.range_u(&key("max_iterations"), k.max_iterations as u64, 1, 1_000_000_000)?;
    c.range_u(&key("gather_ticks"), p.gather_ticks as u64, 0, 1_000_000)?;
    c.range_u(&key("replan.relay_ticks"), p.replan.relay_ticks, 0, 1_000_000)?;
    Ok(())
}

fn finite(f: &FormationSection, c: &Check) -> Result<(), ConfigError> {
    for (i, v) in f.transform.iter().enumerate() {
        if !v.is_finite() {
            return Err(c.err(
                &format!("formation.transform[{i}]"),
                format!("= {v} must be finite ([alpha, d_1, d_2, theta])"),
            ));
        }
    }
    for (i, p) in f.template.iter().enumerate() {
        if !(p[0].is_finite() && p[1].is_finite()) {
            return Err(c.err(
                &format!("formation.template[{i}]"),
                format!("= {p:?} must be finite [x, y]"),
            ));
        }
    }
    Ok(())
}

/// The largest |A| (the similarity's scale) over alpha in `alpha` and theta in `theta` for
/// the reading: literal |alpha - 1 + e^(i theta)| (convex in alpha, so at an end; over theta
/// at an end or a multiple of pi inside), similarity |alpha|.
pub fn max_scale(reading: TransformReading, alpha: [f64; 2], theta: [f64; 2]) -> f64 {
    let mut thetas = vec![theta[0], theta[1]];
    let pi = std::f64::consts::PI;
    let (lo, hi) = ((theta[0] / pi).ceil() as i64, (theta[1] / pi).floor() as i64);
    if hi - lo < 8 {
        thetas.extend((lo..=hi).map(|k| k as f64 * pi));
    } else {
        thetas.extend([0.0, pi]);
    }
    let mut best: f64 = 0.0;
    for a in alpha {
        for &t in &thetas {
            let s = match reading {
                TransformReading::Literal => Transform {
                    alpha: a,
                    d: [0.0, 0.0],
                    theta: t,
                }
                .scale_and_rotation(reading)
                .0,
                TransformReading::Similarity => a.abs(),
            };
            best = best.max(s);
        }
    }
    best
}

/// The closest and the farthest pair of `points`: ((i, j, distance), diameter).
fn spread(points: &[[f64; 2]]) -> (Option<(usize, usize, f64)>, f64) {
    let mut closest: Option<(usize, usize, f64)> = None;
    let mut diameter: f64 = 0.0;
    for i in 0..points.len() {
        for j in i + 1..points.len() {
            let d = (points[i][0] - points[j][0]).hypot(points[i][1] - points[j][1]);
            diameter = diameter.max(d);
            if closest.is_none_or(|(_, _, b)| d < b) {
                closest = Some((i, j, d));
            }
        }
    }
    (closest, diameter)
}

fn template(sc: &Scenario, f: &FormationSection, p: &Params, c: &Check) -> Result<(), ConfigError> {
    let n = sc.run.robots as usize;
    // The world's check names a template that does not fit the robots.
    let Ok(points) = f.template_points(n) else {
        return Ok(());
    };
    let key = f.template_key();
    let k = &p.kernels;
    let r = sc.robot.radius;
    if f.pattern == PatternChoice::Fixed {
        return fixed_slots(sc, f, k, &points, c);
    }
    let (closest, diameter) = spread(&points);
    let Some((i, j, d)) = closest else {
        return Ok(());
    };
    let sep = 2.0 * r + k.separation_margin;
    let theta = if f.pattern == PatternChoice::NoRotation {
        [0.0, 0.0]
    } else {
        k.optimiser.theta_range
    };
    let alpha = k.optimiser.alpha_range;
    let top = max_scale(k.transform_reading, alpha, theta);
    let what = if f.template.is_empty() {
        format!("the built-in letter {:?}", f.template_name)
    } else {
        "the template".to_string()
    };
    if d * top < sep {
        return Err(c.err(
            key,
            format!(
                "{what}'s points {i} and {j} are {d:.3} apart; at the largest scale \
                 formation.kernels.optimiser.alpha_range = {alpha:?} reaches ({top:.3}, theta in \
                 {theta:?}) they are {:.3} apart, less than the separation 2 robot.radius + \
                 formation.kernels.separation_margin = {sep:.3}: no pattern is feasible. Draw \
                 the points at least {:.3} apart, or widen alpha_range",
                d * top,
                sep / top.max(f64::MIN_POSITIVE),
            ),
        ));
    }
    // At the least scale that separates the closest pair the widest pair must fit the box's
    // diagonal (targets keep r from the walls), whatever the rotation.
    let least = sep / d;
    let (w, h) = (sc.arena.width - 2.0 * r, sc.arena.height - 2.0 * r);
    let diagonal = w.max(0.0).hypot(h.max(0.0));
    if diameter * least > diagonal {
        return Err(c.err(
            key,
            format!(
                "{what} is {diameter:.3} across and its closest points {d:.3} apart: scaled \
                 until they are {sep:.3} apart (the separation 2 robot.radius + \
                 formation.kernels.separation_margin) it is {:.3} across, more than the box \
                 (arena.width x arena.height less r at each wall) holds on its diagonal \
                 ({diagonal:.3}): no pattern is feasible. Draw fewer or closer-packed points, or \
                 a larger arena",
                diameter * least
            ),
        ));
    }
    Ok(())
}

/// `pattern = "fixed"`: the slots are the template under `formation.transform`.
fn fixed_slots(
    sc: &Scenario,
    f: &FormationSection,
    k: &crate::formation::FormationParams,
    points: &[[f64; 2]],
    c: &Check,
) -> Result<(), ConfigError> {
    let r = sc.robot.radius;
    let t = Transform {
        alpha: f.transform[0],
        d: [f.transform[1], f.transform[2]],
        theta: f.transform[3],
    };
    let template = Template {
        name: f.template_name.clone(),
        points: points.to_vec(),
    };
    let slots: Vec<[f64; 2]> = t
        .targets(k.transform_reading, &template)
        .iter()
        .map(|q| [q.x, q.y])
        .collect();
    let key = "formation.transform";
    if let (Some((i, j, d)), _) = spread(&slots) {
        if d < 2.0 * r {
            return Err(c.err(
                key,
                format!(
                    "= {:?} (pattern = \"fixed\") puts slots {i} and {j} {d:.3} apart, closer \
                     than 2 robot.radius = {:.3}: the robots could never stand on both. Use a \
                     larger alpha or spread the template",
                    f.transform,
                    2.0 * r
                ),
            ));
        }
    }
    let tol = 1e-9;
    for (i, q) in slots.iter().enumerate() {
        let inside = q[0] >= r - tol
            && q[0] <= sc.arena.width - r + tol
            && q[1] >= r - tol
            && q[1] <= sc.arena.height - r + tol;
        if !inside {
            return Err(c.err(
                key,
                format!(
                    "= {:?} (pattern = \"fixed\") puts slot {i} at [{:.3}, {:.3}], not within \
                     [r, width - r] x [r, height - r] = [{r}, {}] x [{r}, {}] where a robot's \
                     body fits the arena",
                    f.transform,
                    q[0],
                    q[1],
                    sc.arena.width - r,
                    sc.arena.height - r
                ),
            ));
        }
        for (m, disc) in sc.arena.discs.iter().enumerate() {
            let dist = (q[0] - disc.centre[0]).hypot(q[1] - disc.centre[1]);
            if dist < disc.radius + r - tol {
                return Err(c.err(
                    key,
                    format!(
                        "= {:?} (pattern = \"fixed\") puts slot {i} at [{:.3}, {:.3}], {dist:.3} \
                         from arena.discs[{m}] ({:?}), closer than its radius + robot.radius = \
                         {:.3}: no robot can stand there",
                        f.transform,
                        q[0],
                        q[1],
                        disc.name,
                        disc.radius + r
                    ),
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASE: &str = include_str!("../../../../configs/formation.toml");

    /// `BASE` with `extra` appended (and `edit` applied), written to a file of its own (so
    /// the error's line is looked up in it), validated as `orchestrator up` does it.
    fn check_with(name: &str, edit: &dyn Fn(&str) -> String, extra: &str) -> Result<(), ConfigError> {
        let text = format!("{}\n{extra}", edit(BASE));
        let dir = std::env::temp_dir().join(format!("formation-checks-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, &text).unwrap();
        let source = path.to_str().unwrap().to_string();
        let sc = Scenario::parse(&text, &source).unwrap();
        let r = super::super::validate(
            &sc,
            &Check {
                key_source: &|_| source.clone(),
            },
        );
        std::fs::remove_file(&path).unwrap();
        r
    }

    fn check(name: &str, extra: &str) -> Result<(), ConfigError> {
        check_with(name, &|t| t.to_string(), extra)
    }

    /// The error's key, that its source names `name.toml:LINE` and that its message holds
    /// every one of `must`.
    fn refused(r: Result<(), ConfigError>, name: &str, line: usize, key: &str, must: &[&str]) {
        let e = r.expect_err("refused");
        assert_eq!(e.key, key, "{e}");
        assert!(e.source.ends_with(&format!("{name}.toml:{line}")), "{e}");
        for m in must {
            assert!(e.to_string().contains(m), "{m:?} in {e}");
        }
    }

    fn base_lines() -> usize {
        BASE.lines().count() + 1
    }

    #[test]
    fn the_shipped_scenarios_and_a_resolved_one_pass() {
        assert_eq!(check("base", ""), Ok(()));
        for f in [
            "formation-n",
            "formation-r",
            "formation-100",
            "formation-500",
            "formation-swaps-16",
            "formation-100-centralised",
            "formation-500-centralised",
        ] {
            let path = format!("{}/../configs/{f}.toml", env!("CARGO_MANIFEST_DIR"));
            let text = std::fs::read_to_string(&path).unwrap();
            let sc = Scenario::parse(&text, &path).unwrap();
            let c = Check {
                key_source: &|_| path.clone(),
            };
            assert_eq!(super::super::validate(&sc, &c), Ok(()), "{f}");
            // Its resolved scenario (every kernel key written, the derived ones too) passes.
            let mut resolved = sc.clone();
            super::super::resolve(&mut resolved).unwrap();
            assert_eq!(super::super::validate(&resolved, &c), Ok(()), "{f} resolved");
        }
    }

    #[test]
    fn a_typo_under_formation_kernels_is_refused_with_the_allowed_keys() {
        let at = base_lines() + 2;
        refused(
            check("typo", "[formation.kernels]\ntime_stpe = 0.3\n"),
            "typo",
            at,
            "formation.kernels.time_stpe",
            &["not a key of `formation.kernels`", "time_step", "k_a", "optimiser"],
        );
        refused(
            check("typo2", "[formation.kernels.optimiser]\nalpha_rang = [1.0, 1.5]\n"),
            "typo2",
            at,
            "formation.kernels.optimiser.alpha_rang",
            &["formation.kernels.optimiser", "alpha_range", "max_nodes"],
        );
        refused(
            check("typo3", "[formation.kernels.swaps.blocked]\nwait_tick = 3\n"),
            "typo3",
            at,
            "formation.kernels.swaps.blocked.wait_tick",
            &["wait_ticks"],
        );
    }

    #[test]
    fn a_wrong_type_names_its_own_key() {
        let at = base_lines() + 2;
        refused(
            check("type", "[formation.kernels]\nk_a = \"fast\"\n"),
            "type",
            at,
            "formation.kernels.k_a",
            &["wrong type", "expected f64", "default: 1.0"],
        );
        refused(
            check("enum", "[formation.kernels]\nobstacle_constraint = \"cirle\"\n"),
            "enum",
            at,
            "formation.kernels.obstacle_constraint",
            &["square", "circle"],
        );
        refused(
            check("table", "[formation.kernels]\noptimiser = 3\n"),
            "table",
            at,
            "formation.kernels.optimiser",
            &["wrong type"],
        );
        refused(
            check("nested", "[formation.kernels.replan]\nmax_nodes = -4\n"),
            "nested",
            at,
            "formation.kernels.replan.max_nodes",
            &["wrong type"],
        );
    }

    #[test]
    fn a_derived_kernel_key_is_refused_unless_it_holds_the_derived_value() {
        let at = base_lines() + 2;
        refused(
            check("derived", "[formation.kernels]\nepsilon = 0.5\n"),
            "derived",
            at,
            "formation.kernels.epsilon",
            &["formation.epsilon", "0.05"],
        );
        refused(
            check("speed", "[formation.kernels]\nmax_speed = 3\n"),
            "speed",
            at,
            "formation.kernels.max_speed",
            &["robot.v_max"],
        );
        assert_eq!(check("same", "[formation.kernels]\nepsilon = 0.05\nrobot_radius = 1\n"), Ok(()));
    }

    #[test]
    fn the_ranges_params_left_open_are_checked() {
        let at = base_lines() + 2;
        refused(
            check("gap", "[formation.kernels.optimiser]\ngap_rel = 2.0\n"),
            "gap",
            at,
            "formation.kernels.optimiser.gap_rel",
            &["[0, 1]"],
        );
        refused(
            check("slack", "[formation.kernels]\ncell_slack = -1.0\n"),
            "slack",
            at,
            "formation.kernels.cell_slack",
            &["out of range"],
        );
        refused(
            check("iter", "[formation.kernels]\nmax_iterations = 0\n"),
            "iter",
            at,
            "formation.kernels.max_iterations",
            &["1..="],
        );
    }

    fn with_template(points: &str) -> impl Fn(&str) -> String + '_ {
        move |t: &str| {
            t.replace(
                "template_name = \"C\"\n",
                &format!("template_name = \"mine\"\ntemplate = {points}\n"),
            )
        }
    }

    fn template_line() -> usize {
        BASE.lines().position(|l| l.starts_with("template_name")).unwrap() + 2
    }

    #[test]
    fn a_template_no_alpha_separates_is_refused_one_a_larger_alpha_separates_is_not() {
        let line = |step: f64| {
            let p: Vec<String> = (0..9).map(|k| format!("[{}, 0.0]", step * k as f64)).collect();
            format!("[{}]", p.join(", "))
        };
        // 1.5 apart: closer than 2r at alpha = 1, 3.0 apart at alpha = 2 (literal reading,
        // theta = 0): feasible, the optimiser scales it up.
        assert_eq!(check_with("spaced", &with_template(&line(1.5)), ""), Ok(()));
        // 1.0 apart: at most 2.0 apart at the largest scale, less than 2r + 0.2 = 2.2.
        refused(
            check_with("close", &with_template(&line(1.0)), ""),
            "close",
            template_line(),
            "formation.template",
            &["points 0 and 1", "2.200", "alpha_range", "at least 1.100 apart"],
        );
        // ... unless alpha_range reaches further.
        assert_eq!(
            check_with(
                "wide-range",
                &with_template(&line(1.0)),
                "[formation.kernels.optimiser]\nalpha_range = [0.5, 2.5]\n"
            ),
            Ok(())
        );
        // The built-in letter under a narrow alpha_range names template_name.
        let e = check(
            "narrow",
            "[formation.kernels.optimiser]\nalpha_range = [0.6, 0.8]\ntheta_range = [0.0, 0.0]\n",
        )
            .unwrap_err();
        assert_eq!(e.key, "formation.template_name", "{e}");
        // Two points on top of each other.
        refused(
            check_with(
                "dup",
                &with_template("[[0, 0], [0, 0], [0, 4.4], [0, 6.6], [0, 8.8], [2.2, 0], [4.4, 0], [6.6, 0], [8.8, 0]]"),
                "",
            ),
            "dup",
            template_line(),
            "formation.template",
            &["0.000 apart"],
        );
        // A point that is not a number.
        refused(
            check_with(
                "nan",
                &with_template("[[0, 0], [nan, 2.2], [0, 4.4], [0, 6.6], [0, 8.8], [2.2, 0], [4.4, 0], [6.6, 0], [8.8, 0]]"),
                "",
            ),
            "nan",
            template_line(),
            "formation.template[1]",
            &["finite"],
        );
    }

    #[test]
    fn a_template_too_wide_for_the_box_at_its_separating_scale_is_refused() {
        // 9 points: 8 within 1.2 of each other around the origin, one 40 away. Separating the
        // close ones needs scale 1.83; then the template is 73 across, the box's diagonal 31.
        let p = "[[0, 0], [1.2, 0], [2.4, 0], [3.6, 0], [0, 1.2], [1.2, 1.2], [2.4, 1.2], [3.6, 1.2], [40, 0]]";
        refused(
            check_with("wide", &with_template(p), ""),
            "wide",
            template_line(),
            "formation.template",
            &["across", "diagonal", "no pattern is feasible"],
        );
    }

    #[test]
    fn fixed_slots_must_be_apart_inside_the_box_and_off_the_discs() {
        let fixed = |t: [f64; 4]| {
            move |text: &str| {
                text.replace(
                    "pattern = \"optimise\"\n",
                    &format!(
                        "pattern = \"fixed\"\ntransform = [{:?}, {:?}, {:?}, {:?}]\n",
                        t[0], t[1], t[2], t[3]
                    ),
                )
            }
        };
        let at = BASE.lines().position(|l| l.starts_with("pattern =")).unwrap() + 2;
        // The C (radius 3.7, literal reading at alpha 1: s + d) around (18.5, 18.5), clear of
        // the discs at (9, 14) and (15, 9); around (6.4, 11.4) its point 0 (at 45 degrees)
        // lands on OB1's centre.
        assert_eq!(check_with("ok", &fixed([1.0, 18.5, 18.5, 0.0]), ""), Ok(()));
        refused(
            check_with("out", &fixed([1.0, 0.0, 0.0, 0.0]), ""),
            "out",
            at,
            "formation.transform",
            &["slot 1", "not within"],
        );
        refused(
            check_with("disc", &fixed([1.0, 6.4, 11.4, 0.0]), ""),
            "disc",
            at,
            "formation.transform",
            &["arena.discs[0]", "OB1"],
        );
        refused(
            check_with("tight", &fixed([0.5, 12.0, 20.0, 0.0]), ""),
            "tight",
            at,
            "formation.transform",
            &["closer than 2 robot.radius"],
        );
        refused(
            check_with("inf", &fixed([1.0, f64::INFINITY, 0.0, 0.0]), ""),
            "inf",
            at,
            "formation.transform[1]",
            &["finite"],
        );
    }

    #[test]
    fn the_largest_scale_of_the_literal_reading() {
        let pi = std::f64::consts::PI;
        let lit = TransformReading::Literal;
        // |alpha - 1 + e^(i theta)| is largest at theta = 0: alpha.
        assert!((max_scale(lit, [0.5, 2.0], [-pi, pi]) - 2.0).abs() < 1e-12);
        // theta in [pi/2, pi/2]: |1 + i| at alpha = 2.
        assert!((max_scale(lit, [2.0, 2.0], [pi / 2.0, pi / 2.0]) - 2f64.sqrt()).abs() < 1e-12);
        // alpha = 0: |-1 + e^(i theta)| is largest at theta = pi: 2.
        assert!((max_scale(lit, [0.0, 0.0], [-pi, pi]) - 2.0).abs() < 1e-12);
        assert_eq!(max_scale(TransformReading::Similarity, [-3.0, 2.0], [0.0, 1.0]), 3.0);
    }
}
