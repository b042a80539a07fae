//! The part of `orchestrator experiment` for CBCA that runs Example 2 from the thesis's own
//! first allocation (Fig. 4.4(b); `agent::cbca::narrative`, docs/hunting.md 14.6 and 14.8):
//! per radio radius and (2.6) off / on, the imposed start, the groups and their meetings, every
//! (4.22) test, the compensation paid, the utility jumps, the captures, and the narrative's
//! switches side by side with the run's (`agent::cbca::narrative_thesis`), plus a Fig. 4.5
//! SVG per run.

use agent::cbca::model::{Robot, RobotId, Task, TaskId};
use agent::cbca::moving_rounds::{run_moving_from, MovingParams, MovingRun};
use agent::cbca::narrative::{jumps, thesis_start, THESIS_HIDDEN};
use agent::cbca::narrative_thesis::{
    decision_cells, path_names as names, payments, robot_set as set, side_by_side,
};
use agent::cbca::replan::Verdict;
use agent::cbca::CbcaParams;
use std::fmt::Write as _;
use std::path::Path;

use super::fair::CurvesSvg;

fn on_off(cover: bool) -> &'static str {
    if cover {
        "on"
    } else {
        "off"
    }
}

/// The coalitions (task -> members) of a set of paths.
fn coalitions(paths: &[Vec<TaskId>]) -> std::collections::BTreeMap<TaskId, Vec<RobotId>> {
    let mut c: std::collections::BTreeMap<TaskId, Vec<RobotId>> = Default::default();
    for (i, p) in paths.iter().enumerate() {
        for &j in p {
            c.entry(j).or_default().push(i);
        }
    }
    c
}

/// One narrative run at `radius` km with (2.6) `cover`, written to `md`; returns the run.
pub fn narrative_section(
    robots: &[Robot],
    tasks: &[Task],
    params: &CbcaParams,
    radius: f64,
    cover: bool,
    md: &mut String,
) -> MovingRun {
    let mp = MovingParams {
        radius_km: radius,
        ..MovingParams::default()
    };
    let params = CbcaParams {
        enforce_coverage: cover,
        ..params.clone()
    };
    let r = run_moving_from(robots, tasks, &params, &mp, &thesis_start(robots.len()));
    let _ = writeln!(
        md,
        "### Narrative start, radio radius {radius} km, (2.6) {}\n",
        on_off(cover)
    );
    let coal = coalitions(&r.initial_paths);
    let idle: Vec<RobotId> = (0..robots.len())
        .filter(|&i| r.initial_paths[i].is_empty())
        .collect();
    let _ = writeln!(
        md,
        "Start coalitions (imposed): {}; idle {}; T{} hidden until the first meeting. Groups at t = 0 (radio components): {} ({}).\n",
        coal.iter()
            .map(|(j, m)| format!("T{} {}", j + 1, set(m)))
            .collect::<Vec<_>>()
            .join(", "),
        set(&idle),
        THESIS_HIDDEN + 1,
        r.initial_groups.len(),
        r.initial_groups.iter().map(|g| set(g)).collect::<Vec<_>>().join(" ")
    );
    let _ = writeln!(md, "Meetings:\n\n| t | groups that meet | holding (left out) | consensus rounds (fresh + consistency) |\n|---|---|---|---|");
    for rp in &r.replannings {
        let _ = writeln!(
            md,
            "| {:.2} | {} | {} | {} |",
            rp.time,
            rp.groups
                .iter()
                .map(|g| set(g))
                .collect::<Vec<_>>()
                .join(" + "),
            if rp.holding.is_empty() {
                "none".to_string()
            } else {
                set(&rp.holding)
            },
            rp.stats.rounds
        );
    }
    let _ = writeln!(md, "\nEvery (4.22) test (a robot whose fresh proposal differs from its path; sigma = r1 Ē + r2 d_ic + r3 mu):\n\n| t | robot | old path (S) | proposed (S') | gain S' - S | sigma | Ē | d_ic | mu | verdict | path after the consistency pass |\n|---|---|---|---|---|---|---|---|---|---|---|");
    for rp in &r.replannings {
        for d in &rp.decisions {
            let Some(th) = &d.threshold else { continue };
            let _ = writeln!(
                md,
                "| {:.2} | {} | {:.2} | {:.2} | {:.3} | {:.2} | {:.2} | {:?} | {} |",
                rp.time,
                decision_cells(d),
                d.new_score - d.old_score,
                th.sigma,
                th.importance,
                th.sunk_cost,
                th.breach_cost,
                d.verdict,
                names(&d.final_path)
            );
        }
    }
    for rp in &r.replannings {
        let unchanged: Vec<RobotId> = rp
            .decisions
            .iter()
            .filter(|d| d.verdict == Verdict::Unchanged)
            .map(|d| d.robot)
            .collect();
        let moved: Vec<String> = rp
            .decisions
            .iter()
            .filter(|d| d.verdict == Verdict::Unchanged && d.final_path != d.old_path)
            .map(|d| {
                format!(
                    "R{} {} -> {}",
                    d.robot + 1,
                    names(&d.old_path),
                    names(&d.final_path)
                )
            })
            .collect();
        let _ = writeln!(
            md,
            "\nAt t = {:.2}, proposal = old path (no test): {}; of these, changed by the consistency pass: {}.",
            rp.time,
            set(&unchanged),
            if moved.is_empty() {
                "none".to_string()
            } else {
                moved.join(", ")
            }
        );
    }
    let pays: Vec<String> = payments(&r)
        .map(|(time, p)| {
            format!(
                "| {time:.2} | R{} | R{} | T{} | {:.2} |",
                p.from + 1,
                p.to + 1,
                p.task + 1,
                p.amount
            )
        })
        .collect();
    if pays.is_empty() {
        let _ = writeln!(md, "\nCompensation paid: none.\n");
    } else {
        let _ = writeln!(
            md,
            "\nCompensation paid:\n\n| t | from | to | for | amount |\n|---|---|---|---|---|\n{}\n",
            pays.join("\n")
        );
    }
    for k in 0..r.replannings.len() {
        let j = jumps(&r, k);
        let v: Vec<String> = j
            .iter()
            .enumerate()
            .filter(|(_, x)| x.abs() > 1e-6)
            .map(|(i, x)| format!("R{} {x:+.2}", i + 1))
            .collect();
        let _ = writeln!(
            md,
            "Utility jumps at t = {:.2} (Fig. 4.5): {}.\n",
            r.replannings[k].time,
            if v.is_empty() {
                "none".to_string()
            } else {
                v.join(", ")
            }
        );
    }
    let got: Vec<TaskId> = r.captures.iter().map(|c| c.task).collect();
    let missed: Vec<String> = tasks
        .iter()
        .filter(|t| !got.contains(&t.id))
        .map(|t| format!("T{}", t.id + 1))
        .collect();
    let _ = writeln!(
        md,
        "Final coalitions and capture times: {}. Not captured by t = {}: {}.\n",
        r.captures
            .iter()
            .map(|c| format!("T{} {} at {:.2}", c.task + 1, set(&c.members), c.time))
            .collect::<Vec<_>>()
            .join("; "),
        mp.horizon,
        if missed.is_empty() {
            "none".to_string()
        } else {
            missed.join(", ")
        }
    );
    let _ = writeln!(
        md,
        "The thesis's re-planning against this run:\n\n| thesis | this run | why (from the run) |\n|---|---|---|"
    );
    for row in side_by_side(&r) {
        let _ = writeln!(md, "| {} | {} | {} |", row.thesis, row.ours, row.reason);
    }
    let _ = writeln!(md);
    r
}

/// Example 2 from the thesis's first allocation, per radius and (2.6) off / on, with its SVGs.
pub fn example2_narrative(
    robots: &[Robot],
    tasks: &[Task],
    params: &CbcaParams,
    radii: &[f64],
    out: &Path,
    md: &mut String,
    svg: &CurvesSvg,
) -> Result<(), String> {
    let _ = writeln!(
        md,
        "## Example 2 from the thesis's first allocation (narrative start)\n"
    );
    let _ = writeln!(md, "The moving run of the section above (`agent::cbca::moving_rounds`), started from the narrative's Fig. 4.4(b) instead of our CBCA (`agent::cbca::narrative::thesis_start`): the coalitions Phi1-Phi4 imposed as the robots' paths (no CBCA at t = 0), T5 hidden until two groups first meet (the narrative allocates it only at the re-planning), groups = the radio components. Loyalty r1 = {}, r2 = {}, r3 = {}, compensation rate {}. The side-by-side tables are computed from each run (`agent::cbca::narrative_thesis`).\n", params.loyalty.r1, params.loyalty.r2, params.loyalty.r3, params.loyalty.compensation_rate);
    for (cover, &radius) in [false, true]
        .into_iter()
        .flat_map(|c| radii.iter().map(move |r| (c, r)))
    {
        let r = narrative_section(robots, tasks, params, radius, cover, md);
        let tag = if cover { "-2.6-on" } else { "" };
        let file = format!("fig-4.5-narrative-{radius}km{tag}.svg");
        super::fair::utility_svg(
            &r,
            &format!(
                "Example 2 from the thesis's allocation ({radius} km, (2.6) {}): utility against time",
                on_off(cover)
            ),
            &out.join(&file),
            svg,
        )?;
        let _ = writeln!(
            md,
            "![Fig. 4.5, narrative start, {radius} km, (2.6) {}]({file})\n",
            on_off(cover)
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use agent::cbca::scenario::CbcaScenario;

    /// At 2.0 km (the narrative's two groups), the section lists R1's switch (its (4.22) row,
    /// with the run's figures) and every compensation payment R1 makes, which go to R5 and R15.
    #[test]
    fn narrative_section_lists_r1s_switch_and_its_compensation() {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../configs/hunt-cbca-example2.toml"
        ))
        .unwrap();
        let s = CbcaScenario::from_toml(&text).unwrap();
        let (robots, tasks) = (s.robots().unwrap(), s.tasks().unwrap());
        let mut md = String::new();
        let r = narrative_section(
            &robots,
            &tasks,
            &s.params,
            2.0,
            s.params.enforce_coverage,
            &mut md,
        );
        let (rp, d) = r
            .replannings
            .iter()
            .find_map(|rp| rp.decisions.iter().find(|d| d.robot == 0).map(|d| (rp, d)))
            .expect("R1 re-plans");
        assert_eq!(d.verdict, Verdict::Switches);
        let row = format!(
            "| {:.2} | R1 | {} ({:.2}) | {} ({:.2}) | {:.2} | {:.2} |",
            rp.time,
            names(&d.old_path),
            d.old_score,
            names(&d.proposed),
            d.new_score,
            d.new_score - d.old_score,
            d.sigma.unwrap()
        );
        assert!(md.contains(&row), "{row} not in\n{md}");
        let paid: Vec<_> = rp.payments.iter().filter(|p| p.from == 0).collect();
        let mut to: Vec<RobotId> = paid.iter().map(|p| p.to).collect();
        to.sort();
        assert_eq!(to, vec![4, 14], "R1 pays R5 and R15");
        for p in paid {
            let line = format!(
                "| {:.2} | R1 | R{} | T{} | {:.2} |",
                rp.time,
                p.to + 1,
                p.task + 1,
                p.amount
            );
            assert!(md.contains(&line), "{line} not in\n{md}");
        }
        // The side-by-side table's compensation row names the run's payments too.
        let to_r5 = rp
            .payments
            .iter()
            .find(|p| p.from == 0 && p.to == 4)
            .unwrap();
        assert!(md.contains(&format!("R1 -> R5 {:.2}", to_r5.amount)));
    }
}
