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

use crate::experiment::runner::{
    parse_file, run_scenario, tag_of, Context, Report, Row, SeedSpec, DEFAULT_FIRST_SEED,
};
use agent::hunt::auction::run_auction;
use agent::hunt::instance::{random_instance, InstanceParams};
use agent::hunt::parallel_auction::run_parallel_auction;
use agent::hunt::scenario::HuntKernels;
use serde::Deserialize;
use serde_json::Value;
use std::fmt::Write as _;
use std::path::PathBuf;
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
    /// The seeds of a point of the sweeps (the issue: 30): a count (from `first_seed`), a
    /// range "A..B" or a list. `--seeds` / `--runs` override it and `variant_seeds`.
    pub seeds: SeedSpec,
    /// The first seed of a count.
    #[serde(default = "first_seed")]
    pub first_seed: u64,
    /// Fig. 3.7-3.8: n_e fixed, n_r varied.
    pub sweep_robots: Vec<usize>,
    pub sweep_robots_evaders: usize,
    /// Fig. 3.9-3.10: n_r fixed, n_e varied.
    pub sweep_evaders: Vec<usize>,
    pub sweep_evaders_robots: usize,
    /// The seeds a variant of the scenario runs (a count from `first_seed`, a range or a list).
    pub variant_seeds: SeedSpec,
    pub variants: Vec<crate::experiment::Variant>,
    /// The live auctions every variant runs with (`hunt.params.auction`); default: the
    /// scenario's own only.
    #[serde(default)]
    pub auctions: Vec<AuctionKind>,
}

fn first_seed() -> u64 {
    DEFAULT_FIRST_SEED
}

/// Auction names as the tables and rows give them.
fn auction_name(a: AuctionKind) -> String {
    format!("{a:?}").to_lowercase()
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

fn example_3a(
    sc: &Scenario,
    ctx: &Context,
    md: &mut String,
    rows: &mut Vec<Row>,
) -> Result<(), String> {
    let s = ctx.run(sc, "hunt-example-3a")?;
    rows.push(live_row("example 3-A", sc, &s));
    let m = &s["mission"]["hunt"];
    let t5 = sc
        .hunt()
        .evaders
        .iter()
        .find(|e| e.id == 5)
        .map_or(u64::MAX, |e| e.appear_tick(&sc.hunt().params));
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
    let how = match ctx.executor {
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
        s["ticks"].as_f64().unwrap_or(0.0) * sc.hunt().params.minutes_per_tick
    );
    if ctx.executor == crate::up::Executor::Processes {
        let id = format!("{}-hunt-example-3a-inprocess", ctx.id);
        let again = run_scenario(sc, crate::up::Executor::Inprocess, &id)?;
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
        let after = t5 + 2 * sc.hunt().params.replan_period_ticks;
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
            c["tick"].as_f64().unwrap_or(0.0) * sc.hunt().params.minutes_per_tick,
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
    let p = &sc.hunt().params;
    let o = run_auction(&sc.hunt().tasks_at(0.0), &sc.hunt().robots(), p);
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
    for t in sc.hunt().tasks_at(0.0) {
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
    crate::export::charts::write(
        &reward_chart(&series),
        &ctx.out_file("reward-iterations.svg")?,
    )?;
    let _ = writeln!(md, "\n![reward iterations](reward-iterations.svg)\n");
    Ok(())
}

/// Fig. 3.6: each task's reward z_j against the auction round.
fn reward_chart(series: &[(u32, Vec<f64>)]) -> crate::export::charts::Chart {
    use crate::export::charts::{Chart, Point, Series};
    Chart {
        title: "Fig. 3.6 analogue: reward z_j of each task, round by round (initial auction)"
            .into(),
        x_label: "auction round".into(),
        y_label: "reward z_j".into(),
        series: series
            .iter()
            .map(|(id, zs)| Series {
                label: format!("T{id}"),
                points: zs
                    .iter()
                    .enumerate()
                    .map(|(r, &z)| Point {
                        x: (r + 1) as f64,
                        mean: z,
                        lo: z,
                        hi: z,
                    })
                    .collect(),
                reference: false,
            })
            .collect(),
    }
}

/// One point of a sweep: (C, Y) of both auctions over the seeds, and a row per auction run.
fn sweep_point(
    n_e: usize,
    n_r: usize,
    seeds: &[u64],
    p: &agent::hunt::HuntParams,
    figure: &str,
    rows: &mut Vec<Row>,
) -> [Vec<f64>; 6] {
    let ip = InstanceParams::default();
    let mut out: [Vec<f64>; 6] = Default::default();
    for &seed in seeds {
        let (tasks, robots) = random_instance(n_e, n_r, seed, &ip);
        let a = run_auction(&tasks, &robots, p);
        let b = run_parallel_auction(&tasks, &robots, p);
        for (name, cost, utility, coalitions) in [
            (
                "improved",
                a.auctioneer_cost,
                a.total_utility,
                a.coalitions.len(),
            ),
            (
                "parallel",
                b.auctioneer_cost,
                b.total_utility,
                b.coalitions.len(),
            ),
        ] {
            rows.push(
                Row::new(figure, name, n_r as u32, seed)
                    .with("evaders", n_e)
                    .with("C", cost)
                    .with("Y", utility)
                    .with("coalitions", coalitions),
            );
        }
        out[0].push(a.auctioneer_cost);
        out[1].push(b.auctioneer_cost);
        out[2].push(a.total_utility);
        out[3].push(b.total_utility);
        out[4].push(a.coalitions.len() as f64);
        out[5].push(b.coalitions.len() as f64);
    }
    out
}

fn sweeps(
    x: &HuntExperiment,
    seeds: &[u64],
    p: &agent::hunt::HuntParams,
    md: &mut String,
    rows: &mut Vec<Row>,
) {
    let _ = writeln!(
        md,
        "## Figs. 3.7-3.10 as tables (improved vs parallel auction, {} seeds a point, mean ± sd)\n",
        seeds.len()
    );
    let mut table = |title: &str, points: Vec<(usize, usize)>, varied_robots: bool| {
        let figure = if varied_robots {
            "figs 3.7-3.8"
        } else {
            "figs 3.9-3.10"
        };
        let _ = writeln!(md, "### {title}\n");
        let _ = writeln!(md, "| n_e | n_r | C improved | C parallel | Y improved | Y parallel | tasks filled (impr. / par.) |\n|---|---|---|---|---|---|---|");
        let mut c_lower = 0;
        let mut y_higher = 0;
        let mut gaps = Vec::new();
        for (n_e, n_r) in &points {
            let r = sweep_point(*n_e, *n_r, seeds, p, figure, rows);
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

/// A live run as results.csv has it (the capture time empty when not every evader was
/// captured: censored).
fn live_row(variant: &str, sc: &Scenario, s: &Value) -> Row {
    let m = &s["mission"]["hunt"];
    let paid: f64 = m["per_evader"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|e| e["reward_paid"].as_f64())
        .sum();
    Row::new(
        variant,
        auction_name(sc.hunt().params.auction),
        sc.run.robots,
        sc.run.seed,
    )
    .with("evaders", sc.hunt().evaders.len())
    .with("captured", m["captured"].as_f64())
    .with("all_captured", m["all_captured_minutes"].is_number())
    .with("all_captured_minutes", m["all_captured_minutes"].as_f64())
    .with("ticks", s["ticks"].as_u64())
    .with("C", m["auction_cost"].as_f64())
    .with("Y", m["auction_utility"].as_f64())
    .with("reward_paid", paid)
    .with("messages_offered", s["messages"]["offered"].as_u64())
    .with("messages_delivered", s["messages"]["delivered"].as_u64())
    .with("bytes_offered", s["message_bytes"]["offered"].as_u64())
    .with("bytes_delivered", s["message_bytes"]["delivered"].as_u64())
    .with("auction_rounds", m["auction_rounds"].as_u64())
    .with(
        "robots_killed",
        s["faults"].as_array().map_or(0, |f| f.len()),
    )
}

fn variants(
    x: &HuntExperiment,
    base: &Scenario,
    seeds: &[u64],
    ctx: &Context,
    md: &mut String,
    rows: &mut Vec<Row>,
) -> Result<(), String> {
    let auctions = if x.auctions.is_empty() {
        vec![base.hunt().params.auction]
    } else {
        x.auctions.clone()
    };
    let _ = writeln!(
        md,
        "## Live: the auctions over the radio, with radio loss and robots killed ({} seeds a row, the scenario above)\n",
        seeds.len()
    );
    let _ = writeln!(md, "C and Y are those of the auctioneer's auctions as it made the awards (3.13, 3.14; all its auctions: the initial one and the new target's). Reward paid: the sum over the tasks of the last z_j the auctioneer reported (assistance raises it).\n");
    let _ = writeln!(md, "| auction | variant | runs | captured (mean of {}) | all captured | time to the last capture, min (mean over runs that captured all) | C | Y | reward paid | messages offered | delivered | kB offered | kB delivered | bytes a delivered message | auction rounds | robots killed |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|", base.hunt().evaders.len());
    // Every run's scenario first (all validated before any runs), then `--jobs` at a time.
    let mut jobs = Vec::new();
    for auction in &auctions {
        for v in &x.variants {
            for &seed in seeds {
                let mut sc = base.clone();
                sc.run.seed = seed;
                sc.hunt_mut().params.auction = *auction;
                v.apply(&mut sc);
                crate::prepare::prepare_from(&mut sc, &ctx.name()).map_err(|e| e.to_string())?;
                let tag = tag_of(&format!("hunt-{auction:?}-{}-{seed}", v.name));
                jobs.push((sc, tag));
            }
        }
    }
    let mut summaries = ctx.run_all(&jobs).into_iter().zip(&jobs);
    for auction in &auctions {
        for v in &x.variants {
            let mut row = LiveRow::default();
            for _ in seeds {
                let (s, (sc, _)) = summaries.next().expect("a summary a job");
                let s = s?;
                rows.push(live_row(&v.name, sc, &s));
                row.add(&s);
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
                seeds.len(),
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

pub fn run(ctx: &Context) -> Result<Report, String> {
    let mut x: HuntExperiment = parse_file(&ctx.file)?;
    if x.kind != "hunt" {
        return Err(format!("{}: kind = {:?}, not \"hunt\"", ctx.name(), x.kind));
    }
    let seeds = ctx.seeds(&x.seeds, x.first_seed)?;
    let variant_seeds = ctx.seeds(&x.variant_seeds, x.first_seed)?;
    x.scenario = ctx.dir.join(&x.scenario);
    let mut base = Scenario::load(&x.scenario).map_err(|e| e.to_string())?;
    crate::prepare::prepare_from(&mut base, &ctx.name()).map_err(|e| e.to_string())?;
    let mut md = format!(
        "# Hunting, thesis 003 chapter 3 (`orchestrator experiment {}`)\n\n",
        ctx.name()
    );
    let mut rows = Vec::new();
    example_3a(&base, ctx, &mut md, &mut rows)?;
    sweeps(&x, &seeds, &base.hunt().params, &mut md, &mut rows);
    variants(&x, &base, &variant_seeds, ctx, &mut md, &mut rows)?;
    Ok(Report {
        md,
        rows,
        ..Report::default()
    })
}
