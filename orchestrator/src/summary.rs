//! The summary `orchestrator up` prints after a run, from its summary.json: counts with digit
//! grouping, times in ms (the wall time in s), units named, every line wrapped to fit
//! [`COLUMNS`] (continuations indented), and last the command that shows the run in the
//! browser (`orchestrator view runs/<id>`), whole on its own line.

use crate::progress::grouped;
use std::path::Path;

/// No printed line is wider (a word longer than that, a long path, stays whole).
pub const COLUMNS: usize = 80;

/// Prints one line of the summary, wrapped to [`COLUMNS`]; its continuations are indented two
/// columns more than it.
pub fn say(line: &str) {
    let indent = " ".repeat(line.len() - line.trim_start().len() + 2);
    let opts = textwrap::Options::new(COLUMNS)
        .subsequent_indent(&indent)
        .break_words(false);
    for l in textwrap::wrap(line, opts) {
        println!("{l}");
    }
}

/// `println!` through [`say`].
macro_rules! say {
    ($($t:tt)*) => { say(&format!($($t)*)) };
}

/// Robots whose misses the printed summary lists.
const MISSES_LISTED: usize = 20;

/// A count of summary.json as text with digit grouping ("?" when absent).
fn count(v: &serde_json::Value) -> String {
    v.as_u64().map_or_else(|| "?".to_string(), grouped)
}

/// Prints the summary of the run in `dir`; `program` is how the user called the orchestrator
/// (for the command that watches the run).
pub fn print(v: &serde_json::Value, dir: &Path, program: &str) {
    let g = |p: &str| v.pointer(p).cloned().unwrap_or_default();
    let c = |p: &str| count(&g(p));
    let f = |p: &str| v.pointer(p).and_then(|x| x.as_f64()).unwrap_or(0.0);
    say!(
        "run {}  ({} executor, {})",
        g("/run_id").as_str().unwrap_or(""),
        g("/executor").as_str().unwrap_or(""),
        g("/end").as_str().unwrap_or("")
    );
    say!(
        "  robots {}  behaviour {}  seed {}  ticks {}/{}",
        c("/robots"),
        g("/behaviour").as_str().unwrap_or(""),
        g("/seed"),
        c("/ticks"),
        c("/max_ticks")
    );
    say!(
        "  wall {:.2} s (start-up {} ms)  {} ticks/s  tick p50 {:.3} ms  p99 {:.3} ms",
        f("/wall_seconds"),
        grouped((f("/startup_seconds") * 1e3).round() as u64),
        grouped(f("/ticks_per_second").round() as u64),
        f("/tick_time/p50_us") / 1e3,
        f("/tick_time/p99_us") / 1e3
    );
    say!(
        "  messages offered {}  delivered {}  in flight {}",
        c("/messages/offered"),
        c("/messages/delivered"),
        c("/messages/in_flight")
    );
    say!(
        "    dropped: range {}  occluded {}  bandwidth {}  loss {}",
        c("/messages/dropped_range"),
        c("/messages/dropped_occluded"),
        c("/messages/dropped_bandwidth"),
        c("/messages/dropped_loss"),
    );
    say!(
        "    undelivered: malformed {}  receiver dead {}",
        c("/messages/malformed"),
        c("/messages/receiver_dead")
    );
    if let Some(rt) = v.pointer("/realtime") {
        // Robots that missed, as robot:misses (the first MISSES_LISTED; summary.json has all).
        let per: Vec<String> = rt["misses_per_robot"]
            .as_array()
            .map(|a| {
                a.iter()
                    .enumerate()
                    .filter(|(_, x)| x.as_u64().unwrap_or(0) > 0)
                    .take(MISSES_LISTED)
                    .map(|(i, x)| format!("{i}:{x}"))
                    .collect()
            })
            .unwrap_or_default();
        say!(
            "  real-time {} Hz: deadline misses {} of {} robot-ticks ({:.2} %), late actions {}, late releases {}; robot:misses [{}]",
            rt["hz"],
            count(&rt["deadline_misses"]),
            count(&rt["robot_ticks"]),
            100.0 * rt["miss_rate"].as_f64().unwrap_or(0.0),
            count(&rt["late_actions"]),
            count(&rt["late_releases"]),
            per.join(", ")
        );
    }
    let rejected: u64 = v
        .pointer("/rejected_actions")
        .and_then(|r| r.as_object())
        .map(|o| o.values().filter_map(|x| x.as_u64()).sum())
        .unwrap_or(0);
    say!(
        "  rejected actions {}  blocked moves {}  alive at end {}",
        grouped(rejected),
        c("/blocked_moves"),
        c("/alive_at_end")
    );
    if let Some(faults) = v.pointer("/faults").and_then(|x| x.as_array()) {
        for fl in faults {
            say!(
                "  fault: robot {} at tick {}: {}",
                fl["robot"],
                fl["tick"],
                fl["cause"].as_str().unwrap_or("")
            );
        }
    }
    if let Some(sm) = v.pointer("/mission/search") {
        let steps = match sm["steps"].as_u64() {
            Some(s) => grouped(s),
            None => format!("censored at {}", c("/ticks")),
        };
        say!(
            "  search: targets found {}/{}  steps {steps}",
            sm["found"],
            sm["targets"]
        );
        // The paper's energy: the distance the robots moved, all told.
        say!(
            "    energy {} arena units moved",
            grouped(sm["energy"].as_f64().unwrap_or(0.0).round() as u64)
        );
    }
    if let Some(h) = v.pointer("/mission/hunt") {
        print_hunt(h, &g("/ticks"));
    }
    if let Some(fm) = v.pointer("/mission/formation") {
        print_formation(fm, &g("/ticks"), &g("/faults"));
    }
    say!(
        "  mission: coverage {:.1} %  spread {:.1}  mean nearest neighbour {:.1}",
        100.0 * f("/mission/coverage"),
        f("/mission/spread"),
        f("/mission/mean_nearest_neighbour")
    );
    say!(
        "  outputs: {}/{{scenario.toml, summary.json, recording.bin, run.svg}}",
        dir.display()
    );
    // The command stays whole on a line of its own, to copy (however long its paths).
    say("  watch it in the browser:");
    println!("    {program} view {}", dir.display());
}

/// The hunt mission's line of the run summary: evaders captured, when and by whom.
fn print_hunt(h: &serde_json::Value, ticks: &serde_json::Value) {
    let all = match h["all_captured_minutes"].as_f64() {
        Some(m) => format!("all by {m:.2} min"),
        None => format!("not all: censored at tick {ticks}"),
    };
    say!(
        "  hunt: evaders captured {}/{}  {all}",
        h["captured"],
        h["evaders"]
    );
    for e in h["per_evader"].as_array().into_iter().flatten() {
        let by: Vec<String> = e["captured_by"]
            .as_array()
            .into_iter()
            .flatten()
            .map(|r| format!("R{r}"))
            .collect();
        match e["capture_minutes"].as_f64() {
            Some(m) => say!(
                "    T{}: captured at {m:.2} min by {{{}}}",
                e["id"],
                by.join(", ")
            ),
            None => say!("    T{}: not captured", e["id"]),
        }
    }
}

/// The formation mission's line of the run summary: formed or not, K, L, clearances, plans.
/// Whether a plan made at `tick` came after a robot's death (`faults` of the summary): a
/// re-plan, whose "no placement" keeps the previous pattern's slots round the wrecks.
fn after_a_death(faults: &serde_json::Value, tick: &serde_json::Value) -> bool {
    let tick = tick.as_u64().unwrap_or(0);
    faults
        .as_array()
        .into_iter()
        .flatten()
        .any(|f| f["tick"].as_u64().is_some_and(|t| t <= tick))
}

fn print_formation(fm: &serde_json::Value, ticks: &serde_json::Value, faults: &serde_json::Value) {
    let formed = if fm["formed"].as_bool() == Some(true) {
        format!("formed at K = {}", fm["iterations"])
    } else {
        format!("not formed: censored at tick {ticks}")
    };
    let plans: Vec<&serde_json::Value> = fm["plans"].as_array().into_iter().flatten().collect();
    let infeasible: Vec<&&serde_json::Value> = plans
        .iter()
        .filter(|p| p["feasible"].as_bool() == Some(false))
        .collect();
    for p in infeasible
        .iter()
        .filter(|p| after_a_death(faults, &p["tick"]))
    {
        say!(
            "  formation: the re-plan of epoch {} (robot {}, tick {}) after a death found no \
             placement: the robots kept the previous pattern's slots round the wrecks",
            p["epoch"],
            p["robot"],
            p["tick"]
        );
    }
    if infeasible
        .iter()
        .any(|p| !after_a_death(faults, &p["tick"]))
    {
        say!(
            "  formation: NO FEASIBLE PATTERN: the optimiser found no placement of the template \
             inside the box, clear of the discs and 2r + separation_margin apart (within \
             formation.kernels.optimiser.max_nodes); the plan fell back to formation.transform. \
             Move or shrink the discs, enlarge the arena, or widen alpha_range / theta_range"
        );
    }
    say!(
        "  formation: {formed}  robots in place {}/{}  L {:.1}  reassignments {}  overlapping pairs {}",
        fm["robots_in_place"],
        fm["robots"],
        fm["path_length"].as_f64().unwrap_or(0.0),
        fm["reassignments"],
        fm["overlapping_pairs"]
    );
    // A clearance with nothing to measure (one robot, no disc) is infinite, null in JSON.
    let clearance = |v: &serde_json::Value| {
        v.as_f64()
            .map_or_else(|| "none (no pair)".to_string(), |c| format!("{c:.3}"))
    };
    say!(
        "    least clearance: robot-robot {}  robot-obstacle {}",
        clearance(&fm["min_robot_clearance"]),
        clearance(&fm["min_obstacle_clearance"])
    );
    // A swarm that re-plans often (a plan a lost member) lists hundreds: the first and last
    // few, and how many between.
    const SHOWN: usize = 3;
    for (i, p) in plans.iter().enumerate() {
        if plans.len() > 2 * SHOWN && i == SHOWN {
            say!("    ... {} more plans ...", plans.len() - 2 * SHOWN);
        }
        if plans.len() > 2 * SHOWN && (SHOWN..plans.len() - SHOWN).contains(&i) {
            continue;
        }
        if p["epoch"].is_null() {
            // Its parameters come on the next two ticks; a newer plan of the same robot
            // within them takes them (world/src/mission/formation.rs, PlanReport).
            say!(
                "    plan by robot {} at tick {}: superseded before its parameters were reported",
                p["robot"],
                p["tick"]
            );
            continue;
        }
        if p["feasible"].as_bool() == Some(false) && after_a_death(faults, &p["tick"]) {
            say!(
                "    plan epoch {} by robot {} at tick {}: no placement ({} nodes, {:.2} s): the previous pattern kept",
                p["epoch"],
                p["robot"],
                p["tick"],
                p["nodes"],
                p["seconds"].as_f64().unwrap_or(f64::NAN),
            );
            continue;
        }
        if p["feasible"].as_bool() == Some(false) {
            say!(
                "    plan epoch {} by robot {} at tick {}: NO FEASIBLE PATTERN ({} nodes, {:.2} s): fallback alpha {:.3} theta {:.3}",
                p["epoch"],
                p["robot"],
                p["tick"],
                p["nodes"],
                p["seconds"].as_f64().unwrap_or(f64::NAN),
                p["alpha"].as_f64().unwrap_or(f64::NAN),
                p["theta"].as_f64().unwrap_or(f64::NAN),
            );
            continue;
        }
        let gap = p["gap"].as_f64().unwrap_or(f64::NAN);
        say!(
            "    plan epoch {} by robot {} at tick {}: alpha {:.3} theta {:.3}  gap {:.3}{}  {:.2} s",
            p["epoch"],
            p["robot"],
            p["tick"],
            p["alpha"].as_f64().unwrap_or(f64::NAN),
            p["theta"].as_f64().unwrap_or(f64::NAN),
            gap,
            gap_sentinel(gap),
            p["seconds"].as_f64().unwrap_or(f64::NAN)
        );
    }
}

/// What a negative plan gap means: the re-plans report sentinels, not bounds (agent crate:
/// replan.rs `NO_PLACEMENT` = -1, replan_multihop.rs `SHIFTED` = -2 (also the relayed mode's
/// shift, relay_place.rs), shift_drop.rs `SHIFTED_AND_DROPPED` = -3). A gap the optimiser
/// proved is never negative.
fn gap_sentinel(gap: f64) -> &'static str {
    if gap == -1.0 {
        " (no placement found: old transform)"
    } else if gap == -2.0 {
        " (old pattern shifted: no certificate)"
    } else if gap == -3.0 {
        " (shifted, blocked slots dropped: no certificate)"
    } else {
        ""
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plan_made_after_a_death_is_a_re_plan_and_one_before_is_not() {
        let faults = serde_json::json!([{"robot": 3, "tick": 150}, {"robot": 4, "tick": 152}]);
        assert!(!after_a_death(&faults, &serde_json::json!(1)));
        assert!(!after_a_death(&faults, &serde_json::json!(149)));
        assert!(after_a_death(&faults, &serde_json::json!(150)));
        assert!(after_a_death(&faults, &serde_json::json!(164)));
        assert!(!after_a_death(
            &serde_json::json!([]),
            &serde_json::json!(164)
        ));
    }
}
