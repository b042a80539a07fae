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

/// The keys `formation.kernels` may hold: every parameter at its default (the blocked
/// swap's too, which only the swaps mode resolves).
fn allowed() -> toml::Table {
    let mut p = Params::default();
    p.swaps.blocked.get_or_insert_with(BlockedParams::default);
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
    let key = if f.template.is_empty() {
        "formation.template_name"
    } else {
        "formation.template"
    };
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
