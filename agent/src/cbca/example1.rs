//! Example 1 of thesis sec. 4.3 (Tables 4.1, 4.2; spec 8.1) run through the in-memory radio
//! of rounds.rs: the temporary groups, the coalitions beside the thesis's, the idle robots
//! and why, consensus rounds, messages and bytes, with and without grouping. It prints a report
//! (`cargo test --release -p agent --lib cbca::example1 -- --nocapture`) and asserts only what
//! is true of the algorithm, not the thesis's figures.

use std::collections::BTreeMap;

use swarm::geometry::Vec2;

use super::baselines::{self, Allocation};
use super::consensus::CbcaRobot;
use super::dag;
use super::grouping::{comm_graph, robot_knowledge, temporary_groups, PriorInfo};
use super::model::{coverage_shortfall, robot_label, task_label, Robot, RobotId, Task, TaskId};
use super::rounds::{run, Radio, RunStats};
use super::scenario::tests::example;

/// How a run is set up.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Setup {
    /// Radio graph of radius comm_radius_km, knowledge by `PriorInfo`.
    Grouped(PriorInfo),
    /// Every robot hears every other and knows every target (CBCA without grouping).
    Global,
}

struct Outcome {
    robots: Vec<CbcaRobot>,
    groups: Vec<Vec<RobotId>>,
    stats: RunStats,
}

fn setup(robots: &[Robot], tasks: &[Task], setup: Setup) -> (Vec<CbcaRobot>, Vec<Vec<RobotId>>) {
    let s = example(1);
    let pos: Vec<Vec2> = robots.iter().map(|r| r.position).collect();
    let n = robots.len();
    let (knowledge, neighbours) = match setup {
        Setup::Grouped(prior) => (
            robot_knowledge(&pos, tasks, s.params.detection_radius_km, prior),
            comm_graph(&pos, s.params.comm_radius_km),
        ),
        Setup::Global => (
            robot_knowledge(&pos, tasks, 0.0, PriorInfo::Global),
            super::compare::complete_graph(n),
        ),
    };
    let cbca = super::compare::cbca_robots(robots, tasks, &knowledge, &s.params);
    (cbca, neighbours)
}

fn run_example(how: Setup, radio: &Radio) -> Outcome {
    let s = example(1);
    let robots = s.robots().unwrap();
    let tasks = s.tasks().unwrap();
    let (mut cbca, neighbours) = setup(&robots, &tasks, how);
    let stats = run(&mut cbca, &neighbours, radio, s.params.max_iterations);
    let groups = match how {
        Setup::Grouped(_) => temporary_groups(
            &robots.iter().map(|r| r.position).collect::<Vec<_>>(),
            s.params.comm_radius_km,
        ),
        Setup::Global => vec![(0..robots.len()).collect()],
    };
    Outcome {
        robots: cbca,
        groups,
        stats,
    }
}

fn labels(ms: &[RobotId]) -> String {
    ms.iter()
        .map(|&m| robot_label(m))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The coalitions as the group of each task agrees on them: task -> members.
fn coalitions(o: &Outcome) -> BTreeMap<TaskId, Vec<RobotId>> {
    let mut c: BTreeMap<TaskId, Vec<RobotId>> = BTreeMap::new();
    for r in &o.robots {
        for &j in &r.plan().bundle {
            c.entry(j).or_default().push(r.id());
        }
    }
    c
}

/// What is true of the algorithm: converged; inside each group every robot holds the same
/// winner lists and they are the members' bundles; no task over L_j; a DAG; no robot of one
/// group is a winner in another's view.
fn check(o: &Outcome, tasks: &[Task]) {
    assert!(o.stats.converged, "no convergence: {:?}", o.stats);
    for g in &o.groups {
        let first = o.robots[g[0]].winners().entries();
        for &m in g {
            assert_eq!(
                o.robots[m].winners().entries(),
                first,
                "{} disagrees",
                robot_label(m)
            );
            for e in &first {
                assert!(g.contains(&e.robot), "a winner outside the group");
            }
        }
        for t in tasks {
            assert!(o.robots[g[0]].winners().count(t.id) <= t.robots_needed);
        }
    }
    for (j, ms) in coalitions(o) {
        assert!(ms.len() <= tasks[j].robots_needed);
    }
    assert!(dag::is_dag(
        o.robots.iter().map(|r| r.plan().path.as_slice())
    ));
}

fn report(title: &str, o: &Outcome, tasks: &[Task]) {
    println!("== {title}");
    println!(
        "groups: {}",
        o.groups
            .iter()
            .map(|g| format!("{{{}}}", labels(g)))
            .collect::<Vec<_>>()
            .join(" ")
    );
    let c = coalitions(o);
    for t in tasks {
        let ms = c.get(&t.id).cloned().unwrap_or_default();
        let res: Vec<_> = ms.iter().map(|&m| &o.robots[m].robot().resources).collect();
        let short = coverage_shortfall(&res, t);
        let full = ms.len() == t.robots_needed;
        println!(
            "  {}: {{{}}} {}/{} robots{}; (2.6) shortfall {:?}",
            task_label(t.id),
            labels(&ms),
            ms.len(),
            t.robots_needed,
            if full { "" } else { " (INCOMPLETE)" },
            short
        );
    }
    for r in &o.robots {
        if !r.plan().bundle.is_empty() {
            continue;
        }
        let why: Vec<String> = super::idle::why_idle(r, tasks)
            .iter()
            .map(|(j, reason)| format!("{}: {}", task_label(*j), super::idle::describe(reason)))
            .collect();
        println!("  idle {}: {}", robot_label(r.id()), why.join("; "));
    }
    let st = &o.stats;
    println!(
        "  rounds {} (detector), broadcasts {}, bytes {}, copies delivered {}, dropped {}",
        st.rounds, st.broadcasts, st.bytes, st.delivered, st.dropped
    );
}

const THESIS: &str = "thesis (Fig. 4.2): Phi1 = {R3, R6, R5}, Phi2 = {R1, R2, R4}, \
                      Phi3 = {R7, R11, R12}, Phi4 = {R8, R9, R14, R15}; R10, R13 idle";

#[test]
fn example1_grouped_and_global() {
    let tasks = example(1).tasks().unwrap();
    println!("{THESIS}");
    let runs = [
        (
            "grouped, detections only",
            Setup::Grouped(PriorInfo::Detection),
        ),
        (
            "grouped, detections + nearest-robot prior",
            Setup::Grouped(PriorInfo::DetectionPlusNearest),
        ),
        (
            "without grouping (complete graph, all targets)",
            Setup::Global,
        ),
    ];
    let mut stats = Vec::new();
    for (title, how) in runs {
        let o = run_example(how, &Radio::perfect());
        report(title, &o, &tasks);
        check(&o, &tasks);
        stats.push(o.stats.clone());
        if how == Setup::Grouped(PriorInfo::Detection) {
            // Nobody detects T3, so nobody can bid on it.
            assert!(o.robots.iter().all(|r| !r.plan().bundle.contains(&2)));
        }
        if let Setup::Grouped(_) = how {
            assert_eq!(o.groups.len(), 2);
        }
    }
    // Lossy radio, grouped with the prior: same guarantees.
    let lossy = Radio {
        loss: 0.3,
        max_delay: 2,
        seed: 7,
    };
    let o = run_example(Setup::Grouped(PriorInfo::DetectionPlusNearest), &lossy);
    report("grouped + prior, loss 0.3, delay <= 2 rounds", &o, &tasks);
    check(&o, &tasks);
    let o = run_example(Setup::Global, &lossy);
    report("without grouping, loss 0.3, delay <= 2 rounds", &o, &tasks);
    check(&o, &tasks);
}

/// CBCA's Example 1 allocations and the three baselines, scored alike (baselines::evaluate).
#[test]
fn example1_against_the_baselines() {
    let s = example(1);
    let robots = s.robots().unwrap();
    let book = s.task_book().unwrap();
    let tasks = s.tasks().unwrap();
    let mut rows: Vec<(String, Allocation)> = Vec::new();
    for (name, how) in [
        (
            "CBCA grouped + prior",
            Setup::Grouped(PriorInfo::DetectionPlusNearest),
        ),
        ("CBCA without grouping", Setup::Global),
    ] {
        let o = run_example(how, &Radio::perfect());
        check(&o, &tasks);
        rows.push((
            name.to_string(),
            Allocation {
                paths: o.robots.iter().map(|r| r.plan().path.clone()).collect(),
                messages: o.stats.delivered,
            },
        ));
    }
    rows.push((
        "Sujit et al. 2014".into(),
        baselines::sujit::allocate(&robots, &book, &s.params),
    ));
    rows.push((
        "Kim, Baik, Lee 2015".into(),
        baselines::welfare::allocate(&robots, &book, &s.params),
    ));
    rows.push((
        "improved contract net".into(),
        baselines::contract_net::allocate(&robots, &book, &s.params),
    ));
    println!(
        "method | system utility | mean capture time | hunted/shelved | messages | coalitions"
    );
    for (name, a) in &rows {
        let e = baselines::evaluate(&robots, &book, a, &s.params).expect("a DAG");
        for (j, ms) in a.coalitions() {
            assert!(ms.len() <= book[&j].robots_needed, "{name} over L_j on {j}");
        }
        let c: Vec<String> = a
            .coalitions()
            .iter()
            .map(|(j, ms)| format!("{}={{{}}}", task_label(*j), labels(ms)))
            .collect();
        println!(
            "{name} | {:.2} | {:.3} | {}/{} | {} | {}",
            e.system_utility,
            e.mean_completion,
            e.hunted,
            e.shelved,
            a.messages,
            c.join(" ")
        );
    }
}

/// Example 1 under radio loss 0, 0.1, 0.3, 0.5 (delays up to 2 rounds when lossy), 5 seeds a
/// level, with and without grouping: every run must converge and agree (check); the table of
/// rounds, broadcasts and bytes is printed.
#[test]
fn example1_under_radio_loss() {
    let tasks = example(1).tasks().unwrap();
    println!("setup | loss | mean rounds | mean broadcasts | mean kB | mean copies delivered");
    for (name, how) in [
        (
            "grouped + prior",
            Setup::Grouped(PriorInfo::DetectionPlusNearest),
        ),
        ("without grouping", Setup::Global),
    ] {
        for loss in [0.0, 0.1, 0.3, 0.5] {
            let seeds = 5;
            let mut sum = RunStats::default();
            for seed in 0..seeds {
                let radio = Radio {
                    loss,
                    max_delay: if loss > 0.0 { 2 } else { 0 },
                    seed,
                };
                let o = run_example(how, &radio);
                check(&o, &tasks);
                sum.rounds += o.stats.rounds;
                sum.broadcasts += o.stats.broadcasts;
                sum.bytes += o.stats.bytes;
                sum.delivered += o.stats.delivered;
            }
            let n = seeds as f64;
            println!(
                "{name} | {loss} | {:.1} | {:.1} | {:.1} | {:.1}",
                sum.rounds as f64 / n,
                sum.broadcasts as f64 / n,
                sum.bytes as f64 / n / 1000.0,
                sum.delivered as f64 / n
            );
        }
    }
}
