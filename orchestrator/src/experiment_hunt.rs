//! `orchestrator experiment FILE` for a file with `kind = "hunt"` (configs/hunt-experiment.toml;
//! docs/hunting.md section 7): the thesis's chapter 3 experiments.
//!
//! 1. **Example 3-A**, a full run of its scenario (in-process, or with real processes under
//!    `--executor processes`, which then also runs it in-process and says whether both gave
//!    the same results): the initial coalitions and those after T5 beside the thesis's, every
//!    later coalition change (swaps, assistance), the reward paid per task beside Table 3.3
//!    and its cap, and the reward iterations of the initial auction (Fig. 3.6) as
//!    `reward-iterations.svg`.
//! 2. **Figs. 3.7-3.10 as tables**: the improved and the parallel auction on seeded random
//!    instances (`agent::hunt::instance`), C (3.13) and Y (3.14), mean and standard deviation
//!    over `seeds` seeds a point, and whether the thesis's orderings hold.
//! 3. **Live, and beyond the thesis**: runs of the scenario with each auction of `auctions`
//!    (the improved one and the parallel baseline, over the radio: `hunt.params.auction`)
//!    under each variant (radio loss, robots killed): C and Y of the auctions as made,
//!    messages and bytes (the medium's counts), auction rounds, capture rate and time.

use agent::hunt::auction::run_auction;
use agent::hunt::instance::{random_instance, InstanceParams};
use agent::hunt::parallel_auction::run_parallel_auction;
use agent::hunt::scenario::HuntKernels;
use serde::Deserialize;
use serde_json::Value;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use swarm::scenario::Scenario;
use swarm::sections::hunt::AuctionKind;

/// The experiment file of the hunt.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HuntExperiment {
    /// "hunt".
    pub kind: String,
    /// Example 3-A's scenario, relative to the file.
    pub scenario: PathBuf,
    /// Seeds a point of the sweeps (the issue: 30).
    pub seeds: u64,
    /// Fig. 3.7-3.8: n_e fixed, n_r varied.
    pub sweep_robots: Vec<usize>,
    pub sweep_robots_evaders: usize,
    /// Fig. 3.9-3.10: n_r fixed, n_e varied.
    pub sweep_evaders: Vec<usize>,
    pub sweep_evaders_robots: usize,
    /// Runs a variant of the scenario (seeds 1..=variant_seeds).
    pub variant_seeds: u64,
    pub variants: Vec<crate::experiment::Variant>,
    /// The live auctions every variant runs with (`hunt.params.auction`); default: the
    /// scenario's own only.
    #[serde(default)]
    pub auctions: Vec<AuctionKind>,
}

/// How the experiment's runs are made: the executor, and the run id the processes' run ids
/// are made from (one a run, so each has its own /dev/shm names).
struct Runner {
    executor: crate::up::Executor,
    base_id: String,
    made: std::cell::Cell<u32>,
}

impl Runner {
    /// Runs the scenario and returns its summary as JSON.
    fn run(&self, sc: &Scenario, tag: &str) -> Result<Value, String> {
        match self.executor {
            crate::up::Executor::Inprocess => in_process(sc, tag),
            crate::up::Executor::Processes => {
                self.made.set(self.made.get() + 1);
                let id = format!("{}-h{}", self.base_id, self.made.get());
                with_processes(sc, &id)
            }
        }
    }
}

fn in_process(sc: &Scenario, tag: &str) -> Result<Value, String> {
    let s = crate::inprocess::run(sc, None, tag, 1, &mut |_| {}).map_err(|e| e.to_string())?;
    serde_json::to_value(&s).map_err(|e| e.to_string())
}

/// One OS process per agent (the auctioneer too) and the world, as `orchestrator up` runs
/// them; the summary is read back from the run folder, which is then removed.
fn with_processes(sc: &Scenario, run_id: &str) -> Result<Value, String> {
    let dir = std::env::temp_dir().join(format!("swarm-hunt-{run_id}"));
    let summary = crate::processes::run(crate::processes::ProcessRun {
        sc,
        run_id,
        run_dir: &dir,
        live: false,
        on_status: &mut |_| {},
    })
    .and_then(|_| {
        let text = std::fs::read_to_string(dir.join("summary.json"));
        text.map_err(|e| format!("{}: {e}", dir.display()))
    })
    .and_then(|t| serde_json::from_str(&t).map_err(|e| e.to_string()));
    let _ = std::fs::remove_dir_all(&dir);
    summary
}

/// What a run's summary says that must not depend on the executor (not the timings, the
/// executor's name or the run id).
fn outcome_of(s: &Value) -> Value {
    let keys = [
        "end",
        "ticks",
        "messages",
        "rejected_actions",
        "blocked_moves",
        "distance_travelled",
        "alive_at_end",
        "mission",
    ];
    keys.iter()
        .map(|k| (k.to_string(), s[*k].clone()))
        .collect()
}

/// The robot ids of a JSON array (a coalition).
fn ids(v: &Value) -> Vec<u64> {
    v.as_array()
        .map_or(Vec::new(), |a| a.iter().filter_map(Value::as_u64).collect())
}

use crate::experiment::mean_sd;

/// Table 3.3 and the thesis's coalitions (sec. 7.1 of docs/hunting.md).
const TABLE_3_3: [(u32, f64, f64); 5] = [
    (1, 490.0, 520.0),
    (2, 580.0, 640.0),
    (3, 740.0, 820.0),
    (4, 970.0, 1350.0),
    (5, 1450.0, 1600.0),
];
const THESIS_INITIAL: [(u32, &str); 4] = [
    (1, "{R1, R2, R15}"),
    (2, "{R4, R6, R7}"),
    (3, "{R8, R9, R12, R13}"),
    (4, "{R3, R5, R10, R11, R14}"),
];
const THESIS_AFTER_T5: [(u32, &str); 5] = [
    (1, "{R1, R2, R15}"),
    (2, "{R4, R6, R7}"),
    (3, "{R8, R9, R12, R13}"),
    (4, "{R3, R5}"),
    (5, "{R10, R11, R14}"),
];

fn set(v: &[u64]) -> String {
    let names: Vec<String> = v.iter().map(|i| format!("R{i}")).collect();
    format!("{{{}}}", names.join(", "))
}

fn example_3a(sc: &Scenario, run: &Runner, out: &Path, md: &mut String) -> Result<(), String> {
    let s = run.run(sc, "hunt-example-3a")?;
    let m = &s["mission"]["hunt"];
    let t5 = sc
        .hunt
        .evaders
        .iter()
        .find(|e| e.id == 5)
        .map_or(u64::MAX, |e| e.appear_tick(&sc.hunt.params));
    let changes = m["coalition_changes"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    let members_at = |task: u32, before: u64| -> Option<Vec<u64>> {
        changes
            .iter()
            .filter(|c| c["task"] == task && c["tick"].as_u64().unwrap_or(0) < before)
            .map(|c| ids(&c["members"]))
            .rfind(|m| !m.is_empty())
    };
    let _ = writeln!(md, "## Example 3-A (`{}`)\n", sc.run.behaviour);
    let how = match run.executor {
        crate::up::Executor::Inprocess => "in-process",
        crate::up::Executor::Processes => {
            "with real processes (one a robot, the auctioneer, the world)"
        }
    };
    let _ = writeln!(
        md,
        "One run of the scenario (seed {}), {how}. End: {}, {} ticks ({:.1} min).\n",
        sc.run.seed,
        s["end"],
        s["ticks"],
        s["ticks"].as_f64().unwrap_or(0.0) * sc.hunt.params.minutes_per_tick
    );
    if run.executor == crate::up::Executor::Processes {
        let again = in_process(sc, "hunt-example-3a-inprocess")?;
        let (a, b) = (outcome_of(&s), outcome_of(&again));
        let differ: Vec<&String> = a
            .as_object()
            .into_iter()
            .flatten()
            .filter(|(k, v)| b[k.as_str()] != **v)
            .map(|(k, _)| k)
            .collect();
        let _ = writeln!(
            md,
            "The same scenario and seed in-process: {}.\n",
            if differ.is_empty() {
                "the same results (end, ticks, messages, rejected actions, moves, every mission metric)".to_string()
            } else {
                format!("DIFFERENT in {differ:?}")
            }
        );
    }
    let _ = writeln!(md, "| coalition | thesis, initial (Fig. 3.3b) | ours, initial | thesis, after T5 | ours, after T5 (tick {t5}) |\n|---|---|---|---|---|");
    for j in 1..=5u32 {
        let th0 = THESIS_INITIAL
            .iter()
            .find(|x| x.0 == j)
            .map_or("-", |x| x.1);
        let th5 = THESIS_AFTER_T5
            .iter()
            .find(|x| x.0 == j)
            .map_or("-", |x| x.1);
        let ours0 = members_at(j, t5).map_or("-".into(), |v| set(&v));
        // After T5 and its re-planning (the first replanning pass after it).
        let after = t5 + 2 * sc.hunt.params.replan_period_ticks;
        let ours5 = members_at(j, after).map_or("-".into(), |v| set(&v));
        let _ = writeln!(md, "| Phi{j} | {th0} | {ours0} | {th5} | {ours5} |");
    }
    let _ = writeln!(
        md,
        "\nEvery coalition change the robots reported (the robots' own view: swaps, assistance, splits):\n"
    );
    for c in &changes {
        let v = ids(&c["members"]);
        let _ = writeln!(
            md,
            "- tick {} ({:.2} min): T{} = {}",
            c["tick"],
            c["tick"].as_f64().unwrap_or(0.0) * sc.hunt.params.minutes_per_tick,
            c["task"],
            set(&v)
        );
    }
    let _ = writeln!(
        md,
        "\n| task | reward paid, thesis (Table 3.3) | ours | cap z_max | ours under the cap | captured at (min) | by |\n|---|---|---|---|---|---|---|"
    );
    for e in m["per_evader"].as_array().cloned().unwrap_or_default() {
        let id = e["id"].as_u64().unwrap_or(0) as u32;
        let th = TABLE_3_3.iter().find(|x| x.0 == id);
        let z = e["reward_paid"].as_f64();
        let cap = e["reward_cap"].as_f64().unwrap_or(0.0);
        let by = ids(&e["captured_by"]);
        let _ = writeln!(
            md,
            "| T{id} | {} | {} | {cap} | {} | {} | {} |",
            th.map_or("-".into(), |t| format!("{}", t.1)),
            z.map_or("-".into(), |z| format!("{z:.1}")),
            z.map_or("-", |z| if z <= cap { "yes" } else { "NO" }),
            e["capture_minutes"]
                .as_f64()
                .map_or("not captured".into(), |t| format!("{t:.2}")),
            set(&by)
        );
    }
    let _ = writeln!(
        md,
        "\nAuction rounds the auctioneer ran (all its auctions): {}. Messages offered {}, delivered {}; bytes offered {}, delivered {}.\n",
        m["auction_rounds"], s["messages"]["offered"], s["messages"]["delivered"],
        s["message_bytes"]["offered"], s["message_bytes"]["delivered"]
    );
    // Fig. 3.6: the initial auction's rewards round by round (the kernel, lossless: the same
    // rounds as the auctioneer's first auction over a lossless radio).
    let p = &sc.hunt.params;
    let o = run_auction(&sc.hunt.tasks_at(0.0), &sc.hunt.robots(), p);
    let _ = writeln!(
        md,
        "Reward iterations of the initial auction (Fig. 3.6; thesis: T3, T4 rise, T1, T2 fall, flat after 12): {} rounds, finish {:?}.\n",
        o.rounds.len(),
        o.finish
    );
    let _ = writeln!(
        md,
        "| task | z round 1 | z last | trend |\n|---|---|---|---|"
    );
    let mut series: Vec<(u32, Vec<f64>)> = Vec::new();
    for t in sc.hunt.tasks_at(0.0) {
        let zs: Vec<f64> = o
            .rounds
            .iter()
            .filter_map(|r| r.rewards.get(&t.id).copied())
            .collect();
        if let (Some(a), Some(b)) = (zs.first(), zs.last()) {
            let trend = if b > a {
                "rises"
            } else if b < a {
                "falls"
            } else {
                "flat"
            };
            let _ = writeln!(md, "| T{} | {a:.1} | {b:.1} | {trend} |", t.id);
        }
        series.push((t.id, zs));
    }
    write_reward_svg(&series, &out.join("reward-iterations.svg"))?;
    let _ = writeln!(md, "\n![reward iterations](reward-iterations.svg)\n");
    Ok(())
}

/// Fig. 3.6 as an SVG: one polyline a task, reward against round.
fn write_reward_svg(series: &[(u32, Vec<f64>)], path: &Path) -> Result<(), String> {
    let (w, h, pad) = (640.0, 400.0, 50.0);
    let rounds = series.iter().map(|s| s.1.len()).max().unwrap_or(1).max(2);
    let zmax = series
        .iter()
        .flat_map(|s| s.1.iter().copied())
        .fold(1.0, f64::max);
    let x = |r: usize| pad + (w - 2.0 * pad) * r as f64 / (rounds - 1) as f64;
    let y = |z: f64| h - pad - (h - 2.0 * pad) * z / (zmax * 1.05);
    let colours = ["#dc2828", "#2878dc", "#1ea03c", "#e68c00", "#963cc8"];
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\"><rect width=\"100%\" height=\"100%\" fill=\"white\"/>\
         <line x1=\"{pad}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"black\"/><line x1=\"{pad}\" y1=\"{pad}\" x2=\"{pad}\" y2=\"{}\" stroke=\"black\"/>\
         <text x=\"{}\" y=\"{}\" font-size=\"13\">auction round</text><text x=\"8\" y=\"{}\" font-size=\"13\">z_j</text>",
        h - pad, w - pad, h - pad, h - pad, w / 2.0 - 40.0, h - 12.0, pad - 10.0
    );
    for (k, (id, zs)) in series.iter().enumerate() {
        let c = colours[k % colours.len()];
        let pts: Vec<String> = zs
            .iter()
            .enumerate()
            .map(|(r, z)| format!("{:.1},{:.1}", x(r), y(*z)))
            .collect();
        let _ = write!(
            svg,
            "<polyline fill=\"none\" stroke=\"{c}\" stroke-width=\"2\" points=\"{}\"/><text x=\"{}\" y=\"{}\" fill=\"{c}\" font-size=\"13\">T{id}</text>",
            pts.join(" "),
            w - pad + 5.0,
            y(*zs.last().unwrap_or(&0.0)) + 4.0
        );
    }
    svg.push_str("</svg>\n");
    std::fs::write(path, svg).map_err(|e| format!("{}: {e}", path.display()))
}

/// One point of a sweep: (C, Y) of both auctions over the seeds.
fn sweep_point(n_e: usize, n_r: usize, seeds: u64, p: &agent::hunt::HuntParams) -> [Vec<f64>; 6] {
    let ip = InstanceParams::default();
    let mut out: [Vec<f64>; 6] = Default::default();
    for seed in 1..=seeds {
        let (tasks, robots) = random_instance(n_e, n_r, seed, &ip);
        let a = run_auction(&tasks, &robots, p);
        let b = run_parallel_auction(&tasks, &robots, p);
        out[0].push(a.auctioneer_cost);
        out[1].push(b.auctioneer_cost);
        out[2].push(a.total_utility);
        out[3].push(b.total_utility);
        out[4].push(a.coalitions.len() as f64);
        out[5].push(b.coalitions.len() as f64);
    }
    out
}

fn sweeps(x: &HuntExperiment, p: &agent::hunt::HuntParams, md: &mut String) {
    let _ = writeln!(
        md,
        "## Figs. 3.7-3.10 as tables (improved vs parallel auction, {} seeds a point, mean ± sd)\n",
        x.seeds
    );
    let mut table = |title: &str, points: Vec<(usize, usize)>, varied_robots: bool| {
        let _ = writeln!(md, "### {title}\n");
        let _ = writeln!(md, "| n_e | n_r | C improved | C parallel | Y improved | Y parallel | tasks filled (impr. / par.) |\n|---|---|---|---|---|---|---|");
        let mut c_lower = 0;
        let mut y_higher = 0;
        let mut gaps = Vec::new();
        for (n_e, n_r) in &points {
            let r = sweep_point(*n_e, *n_r, x.seeds, p);
            let s: Vec<(f64, f64)> = r.iter().map(|v| mean_sd(v)).collect();
            let _ = writeln!(
                md,
                "| {n_e} | {n_r} | {:.0} ± {:.0} | {:.0} ± {:.0} | {:.0} ± {:.0} | {:.0} ± {:.0} | {:.1} / {:.1} |",
                s[0].0, s[0].1, s[1].0, s[1].1, s[2].0, s[2].1, s[3].0, s[3].1, s[4].0, s[5].0
            );
            c_lower += (s[0].0 < s[1].0) as usize;
            y_higher += (s[2].0 > s[3].0) as usize;
            gaps.push(s[2].0 - s[3].0);
        }
        let growing = gaps.windows(2).filter(|w| w[1] > w[0]).count();
        let _ = writeln!(
            md,
            "\nOrderings: C improved < C parallel at {c_lower} of {} points; Y improved > Y parallel at {y_higher} of {}; the Y gap grows from one point to the next {growing} of {} times{}.\n",
            points.len(),
            points.len(),
            points.len().saturating_sub(1),
            if varied_robots { " (thesis: it grows with n_r)" } else { "" }
        );
    };
    table(
        &format!(
            "Figs. 3.7 (C) and 3.8 (Y): n_e = {}, n_r varied",
            x.sweep_robots_evaders
        ),
        x.sweep_robots
            .iter()
            .map(|&n_r| (x.sweep_robots_evaders, n_r))
            .collect(),
        true,
    );
    table(
        &format!(
            "Figs. 3.9 (C) and 3.10 (Y): n_r = {}, n_e varied",
            x.sweep_evaders_robots
        ),
        x.sweep_evaders
            .iter()
            .map(|&n_e| (n_e, x.sweep_evaders_robots))
            .collect(),
        false,
    );
}

/// One row of the live table: the means over the seeds of a (auction, variant).
#[derive(Default)]
struct LiveRow {
    captured: Vec<f64>,
    all: usize,
    times: Vec<f64>,
    cost: Vec<f64>,
    utility: Vec<f64>,
    paid: Vec<f64>,
    offered: Vec<f64>,
    delivered: Vec<f64>,
    bytes_offered: Vec<f64>,
    bytes_delivered: Vec<f64>,
    rounds: Vec<f64>,
    killed: Vec<f64>,
}

impl LiveRow {
    fn add(&mut self, s: &Value) {
        let m = &s["mission"]["hunt"];
        self.captured.push(m["captured"].as_f64().unwrap_or(0.0));
        if let Some(t) = m["all_captured_minutes"].as_f64() {
            self.all += 1;
            self.times.push(t);
        }
        self.cost.extend(m["auction_cost"].as_f64());
        self.utility.extend(m["auction_utility"].as_f64());
        let paid = m["per_evader"].as_array().into_iter().flatten();
        self.paid
            .push(paid.filter_map(|e| e["reward_paid"].as_f64()).sum::<f64>());
        self.offered
            .push(s["messages"]["offered"].as_f64().unwrap_or(0.0));
        self.delivered
            .push(s["messages"]["delivered"].as_f64().unwrap_or(0.0));
        self.bytes_offered
            .push(s["message_bytes"]["offered"].as_f64().unwrap_or(0.0));
        self.bytes_delivered
            .push(s["message_bytes"]["delivered"].as_f64().unwrap_or(0.0));
        self.rounds
            .push(m["auction_rounds"].as_f64().unwrap_or(0.0));
        self.killed
            .push(s["faults"].as_array().map_or(0, |f| f.len()) as f64);
    }
}

fn variants(
    x: &HuntExperiment,
    base: &Scenario,
    file: &str,
    run: &Runner,
    md: &mut String,
) -> Result<(), String> {
    let auctions = if x.auctions.is_empty() {
        vec![base.hunt.params.auction]
    } else {
        x.auctions.clone()
    };
    let _ = writeln!(
        md,
        "## Live: the auctions over the radio, with radio loss and robots killed ({} seeds a row, the scenario above)\n",
        x.variant_seeds
    );
    let _ = writeln!(md, "C and Y are those of the auctioneer's auctions as it made the awards (3.13, 3.14; all its auctions: the initial one and the new target's). Reward paid: the sum over the tasks of the last z_j the auctioneer reported (assistance raises it).\n");
    let _ = writeln!(md, "| auction | variant | runs | captured (mean of {}) | all captured | time to the last capture, min (mean over runs that captured all) | C | Y | reward paid | messages offered | delivered | kB offered | kB delivered | bytes a delivered message | auction rounds | robots killed |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|", base.hunt.evaders.len());
    for auction in &auctions {
        for v in &x.variants {
            let mut row = LiveRow::default();
            for seed in 1..=x.variant_seeds {
                let mut sc = base.clone();
                sc.run.seed = seed;
                sc.hunt.params.auction = *auction;
                v.apply(&mut sc);
                crate::prepare::prepare_from(&mut sc, file).map_err(|e| e.to_string())?;
                let tag: String = format!("hunt-{auction:?}-{}-{seed}", v.name)
                    .chars()
                    .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
                    .collect();
                row.add(&run.run(&sc, &tag)?);
            }
            let ms = |v: &[f64]| {
                if v.is_empty() {
                    "-".to_string()
                } else {
                    let (m, sd) = mean_sd(v);
                    format!("{m:.0} ± {sd:.0}")
                }
            };
            let _ = writeln!(
                md,
                "| {auction:?} | {} | {} | {:.2} | {} | {} | {} | {} | {} | {:.0} | {:.0} | {:.0} | {:.0} | {:.1} | {:.1} | {:.1} |",
                v.name,
                x.variant_seeds,
                mean_sd(&row.captured).0,
                row.all,
                if row.times.is_empty() {
                    "-".to_string()
                } else {
                    format!("{:.1} ± {:.1}", mean_sd(&row.times).0, mean_sd(&row.times).1)
                },
                ms(&row.cost),
                ms(&row.utility),
                ms(&row.paid),
                mean_sd(&row.offered).0,
                mean_sd(&row.delivered).0,
                mean_sd(&row.bytes_offered).0 / 1000.0,
                mean_sd(&row.bytes_delivered).0 / 1000.0,
                mean_sd(&row.bytes_delivered).0 / mean_sd(&row.delivered).0.max(1.0),
                mean_sd(&row.rounds).0,
                mean_sd(&row.killed).0
            );
        }
    }
    let _ = writeln!(
        md,
        "\nMessages are (message, receiver) pairs (a broadcast counts once per other live agent). Bytes are the medium's count (summary `message_bytes`): each pair's encoded payload (bincode, the size the sender's radio header carries), offered and delivered, in kB (1000 bytes), means over the runs.\n"
    );
    Ok(())
}

pub fn run(
    file: &Path,
    out: Option<&Path>,
    executor: crate::up::Executor,
    runs: Option<u32>,
) -> Result<i32, String> {
    let text = std::fs::read_to_string(file)
        .map_err(|e| format!("{}: cannot read: {e}", file.display()))?;
    let mut x: HuntExperiment =
        toml::from_str(&text).map_err(|e| format!("{}: {}", file.display(), e.message()))?;
    if x.kind != "hunt" {
        return Err(format!(
            "{}: kind = {:?}, not \"hunt\"",
            file.display(),
            x.kind
        ));
    }
    // `--runs N`: N seeds a sweep point and a live row instead of the file's.
    if let Some(n) = runs {
        x.seeds = n.into();
        x.variant_seeds = n.into();
    }
    x.scenario = file.parent().unwrap_or(Path::new(".")).join(&x.scenario);
    let mut base = Scenario::load(&x.scenario).map_err(|e| e.to_string())?;
    let name = file.display().to_string();
    crate::prepare::prepare_from(&mut base, &name).map_err(|e| e.to_string())?;
    let out = out.map_or_else(
        || Path::new("runs").join(format!("experiment-{}", crate::runid::new_run_id())),
        Path::to_path_buf,
    );
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let mut md = format!(
        "# Hunting, thesis 003 chapter 3 (`orchestrator experiment {}`)\n\n",
        file.display()
    );
    let run = Runner {
        executor,
        base_id: crate::runid::new_run_id(),
        made: std::cell::Cell::new(0),
    };
    example_3a(&base, &run, &out, &mut md)?;
    sweeps(&x, &base.hunt.params, &mut md);
    variants(&x, &base, &name, &run, &mut md)?;
    std::fs::write(out.join("results.md"), &md).map_err(|e| e.to_string())?;
    println!("{md}");
    println!("results: {}", out.join("results.md").display());
    Ok(0)
}
