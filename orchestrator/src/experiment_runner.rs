//! What every experiment kind shares, naming no paper: the flags, the seeds, the output folder,
//! one way to run a scenario with either executor, and the results files. A kind turns its runs
//! into [`Row`]s (one a run: variant, mode, N, seed, its metrics) and its tables into a
//! [`Report`] over them; [`write_results`] writes `results.md`, `results.json` and
//! `results.csv` under `--out` and nowhere else.

use crate::up::Executor;
use crate::{inprocess, processes, runid};
use clap::Args;
use serde::{Deserialize, Deserializer};
use serde_json::{Map, Value};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use swarm::scenario::Scenario;

/// Where an experiment writes when `--out` is not given, relative to the working directory
/// (`runs/` is ignored by git): `runs/experiments/<file stem>-<run id>`.
pub const DEFAULT_OUT_ROOT: &str = "runs/experiments";

/// The first seed of a seed count (`seeds = 10`) when the file gives no `first_seed`.
pub const DEFAULT_FIRST_SEED: u64 = 1;

/// The results files every experiment writes under `--out`.
pub const RESULTS_MD: &str = "results.md";
pub const RESULTS_JSON: &str = "results.json";
pub const RESULTS_CSV: &str = "results.csv";

#[derive(Args, Debug)]
pub struct ExperimentArgs {
    /// Experiment file (TOML), e.g. configs/search-table5.toml.
    pub file: PathBuf,
    /// Seeds instead of the file's `seeds`: a range A..B (both ends included) or a list a,b,c.
    #[arg(long, value_parser = SeedSpec::parse_flag)]
    pub seeds: Option<SeedSpec>,
    /// Seeds a set (overrides the file's count; from the first of the seeds; with a list of
    /// seeds, its first K).
    #[arg(long)]
    pub runs: Option<u32>,
    /// Where each run's robots run: in one process (fast sweeps) or as real processes.
    #[arg(long, value_enum, default_value_t = Executor::Inprocess)]
    pub executor: Executor,
    /// The folder results.md, results.json, results.csv and the charts go to; nothing is
    /// written anywhere else [default: runs/experiments/<file stem>-<run id>].
    #[arg(short, long)]
    pub out: Option<PathBuf>,
    /// Runs at once (in-process executor) [default: the number of cores; processes: 1].
    #[arg(long)]
    pub jobs: Option<usize>,
    /// No progress output (the tables are still printed).
    #[arg(short, long)]
    pub quiet: bool,
}

/// Why a seed set cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SeedError {
    #[error("{0:?} is not a seed: allowed a range A..B (both ends included), a list a,b,c, or (in a file) a count")]
    NotASeed(String),
    #[error("the range {0}..{1} is empty: its start must not be above its end")]
    Reversed(u64, u64),
    #[error("no seeds given")]
    Empty,
    #[error("seed {0} is given twice")]
    Repeated(u64),
    #[error("--runs {runs}: the seed list has only {have} seeds")]
    TooFew { runs: u32, have: usize },
}

/// A set of seeds as a file's `seeds` key or `--seeds` gives it.
#[derive(Debug, Clone, PartialEq)]
pub enum SeedSpec {
    /// `seeds = 10`: 10 seeds from the file's `first_seed` on.
    Count(u64),
    /// `seeds = "9001..9010"` / `--seeds 9001..9010`: both ends included.
    Range(u64, u64),
    /// `seeds = [3, 5, 8]` / `--seeds 3,5,8`.
    List(Vec<u64>),
}

impl SeedSpec {
    /// `A..B` / `A..=B` (both ends included) or `a,b,c` (one seed is a list of one).
    pub fn parse(s: &str) -> Result<SeedSpec, SeedError> {
        let num = |t: &str| {
            t.trim()
                .parse::<u64>()
                .map_err(|_| SeedError::NotASeed(s.to_string()))
        };
        if let Some((a, b)) = s.split_once("..") {
            let (a, b) = (num(a)?, num(b.strip_prefix('=').unwrap_or(b))?);
            if a > b {
                return Err(SeedError::Reversed(a, b));
            }
            return Ok(SeedSpec::Range(a, b));
        }
        let list = s.split(',').map(num).collect::<Result<Vec<_>, _>>()?;
        SeedSpec::List(list).checked()
    }

    /// clap's parser for `--seeds`.
    fn parse_flag(s: &str) -> Result<SeedSpec, String> {
        SeedSpec::parse(s).map_err(|e| e.to_string())
    }

    fn checked(self) -> Result<SeedSpec, SeedError> {
        if let SeedSpec::List(v) = &self {
            if v.is_empty() {
                return Err(SeedError::Empty);
            }
            let mut sorted = v.clone();
            sorted.sort_unstable();
            if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
                return Err(SeedError::Repeated(w[0]));
            }
        }
        Ok(self)
    }

    /// The seeds, a count starting at `first`; `runs` (`--runs K`) takes K seeds from the
    /// first on (a count or range is extended or cut, a list cut).
    pub fn seeds(&self, first: u64, runs: Option<u32>) -> Result<Vec<u64>, SeedError> {
        let (start, all): (u64, Vec<u64>) = match self {
            SeedSpec::Count(n) => (first, (first..first + n).collect()),
            SeedSpec::Range(a, b) => (*a, (*a..=*b).collect()),
            SeedSpec::List(v) => (v[0], v.clone()),
        };
        match (runs, self) {
            (None, _) => Ok(all),
            (Some(k), SeedSpec::List(v)) if k as usize > v.len() => Err(SeedError::TooFew {
                runs: k,
                have: v.len(),
            }),
            (Some(k), SeedSpec::List(v)) => Ok(v[..k as usize].to_vec()),
            (Some(k), _) => Ok((start..start + k as u64).collect()),
        }
    }
}

impl<'de> Deserialize<'de> for SeedSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = SeedSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "a count of seeds (10), a range \"9001..9010\" (both ends included) or a list [3, 5, 8]",
                )
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<SeedSpec, E> {
                u64::try_from(v)
                    .map(SeedSpec::Count)
                    .map_err(|_| E::custom(format!("{v}: a count of seeds cannot be negative")))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<SeedSpec, E> {
                Ok(SeedSpec::Count(v))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<SeedSpec, E> {
                SeedSpec::parse(v).map_err(E::custom)
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut a: A,
            ) -> Result<SeedSpec, A::Error> {
                let mut v = Vec::new();
                while let Some(s) = a.next_element::<u64>()? {
                    v.push(s);
                }
                SeedSpec::List(v)
                    .checked()
                    .map_err(serde::de::Error::custom)
            }
        }
        d.deserialize_any(V)
    }
}

impl serde::Serialize for SeedSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            SeedSpec::Count(n) => s.serialize_u64(*n),
            SeedSpec::Range(a, b) => s.serialize_str(&format!("{a}..{b}")),
            SeedSpec::List(v) => v.serialize(s),
        }
    }
}

/// Parses an experiment file as `T`; an error names the file, the line and the key.
pub fn parse_file<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    toml::from_str(&text).map_err(|e| {
        let line = e
            .span()
            .map(|s| text[..s.start.min(text.len())].lines().count().max(1));
        match line {
            Some(l) => format!("{}:{l}: {}", path.display(), e.message()),
            None => format!("{}: {}", path.display(), e.message()),
        }
    })
}

/// One experiment as the flags set it up: where it reads and writes, how it runs.
#[derive(Debug)]
pub struct Context {
    /// The experiment file, and its folder (scenario paths in it are relative to it).
    pub file: PathBuf,
    pub dir: PathBuf,
    /// The results folder (`--out`); made by [`Context::out_file`] when the first file is
    /// written, so bad input leaves nothing behind.
    pub out: PathBuf,
    /// The experiment's id; its runs' ids (and /dev/shm names) are made from it.
    pub id: String,
    pub executor: Executor,
    /// Runs at once.
    pub jobs: usize,
    pub quiet: bool,
    seeds: Option<SeedSpec>,
    runs: Option<u32>,
}

impl Context {
    /// From the flags.
    pub fn new(a: &ExperimentArgs) -> Result<Context, String> {
        let id = runid::new_run_id();
        let stem = a
            .file
            .file_stem()
            .map_or("experiment".into(), |s| s.to_string_lossy().into_owned());
        let out = a
            .out
            .clone()
            .unwrap_or_else(|| Path::new(DEFAULT_OUT_ROOT).join(format!("{stem}-{id}")));
        let jobs = match a.executor {
            Executor::Inprocess => a
                .jobs
                .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
            Executor::Processes => 1,
        };
        Ok(Context {
            file: a.file.clone(),
            dir: a.file.parent().unwrap_or(Path::new(".")).to_path_buf(),
            out,
            id,
            executor: a.executor,
            jobs: jobs.max(1),
            quiet: a.quiet,
            seeds: a.seeds.clone(),
            runs: a.runs,
        })
    }

    /// The seeds of a set the file gives as `file_seeds` (a count from `first`), after
    /// `--seeds` and `--runs`.
    pub fn seeds(&self, file_seeds: &SeedSpec, first: u64) -> Result<Vec<u64>, String> {
        let spec = self.seeds.as_ref().unwrap_or(file_seeds);
        spec.seeds(first, self.runs).map_err(|e| match &self.seeds {
            Some(_) => format!("--seeds: {e}"),
            None => format!("{}: seeds: {e}", self.file.display()),
        })
    }

    /// The results folder (`--out`), made if need be.
    pub fn out_dir(&self) -> Result<&Path, String> {
        std::fs::create_dir_all(&self.out)
            .map_err(|e| format!("--out {}: {e}", self.out.display()))?;
        Ok(&self.out)
    }

    /// The path of the results file `name` under `--out`, the folder made if need be.
    pub fn out_file(&self, name: &str) -> Result<PathBuf, String> {
        Ok(self.out_dir()?.join(name))
    }

    /// The experiment file's name as the reports print it.
    pub fn name(&self) -> String {
        self.file.display().to_string()
    }

    /// Runs `sc` with the experiment's executor and returns its summary as JSON. `tag` makes
    /// the run's id (and its /dev/shm names) unique within the experiment; a processes run's
    /// folder is a temporary one, removed after its summary is read.
    pub fn run(&self, sc: &Scenario, tag: &str) -> Result<Value, String> {
        run_scenario(sc, self.executor, &format!("{}-{tag}", self.id))
    }
}

impl Context {
    /// Runs every (scenario, tag) of `jobs`, `--jobs` at a time, and returns their summaries
    /// in the jobs' order (see [`Context::run`]).
    pub fn run_all(&self, jobs: &[(Scenario, String)]) -> Vec<Result<Value, String>> {
        let next = AtomicUsize::new(0);
        let done: Mutex<Vec<(usize, Result<Value, String>)>> = Mutex::new(Vec::new());
        std::thread::scope(|s| {
            for _ in 0..self.jobs.min(jobs.len()).max(1) {
                s.spawn(|| loop {
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    let Some((sc, tag)) = jobs.get(i) else { break };
                    let r = self.run(sc, tag);
                    if !self.quiet {
                        eprintln!("run {}/{}: {tag}", i + 1, jobs.len());
                    }
                    done.lock().expect("lock").push((i, r));
                });
            }
        });
        let mut v = done.into_inner().expect("lock");
        v.sort_by_key(|x| x.0);
        v.into_iter().map(|x| x.1).collect()
    }
}

/// A run's tag from free text (a variant's name): letters and digits, the rest '-'.
pub fn tag_of(text: &str) -> String {
    text.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect()
}

/// Runs `sc` (see [`Context::run`]) under the run id `run_id`.
pub fn run_scenario(sc: &Scenario, executor: Executor, run_id: &str) -> Result<Value, String> {
    match executor {
        Executor::Inprocess => inprocess::run(sc, None, run_id, 1, &mut |_| {})
            .map_err(|e| e.to_string())
            .and_then(|s| serde_json::to_value(&s).map_err(|e| e.to_string())),
        Executor::Processes => {
            let dir = std::env::temp_dir().join(format!("swarm-exp-{run_id}"));
            let r = processes::run(processes::ProcessRun {
                sc,
                run_id,
                run_dir: &dir,
                live: false,
                on_status: &mut |_| {},
            })
            .and_then(|_| {
                std::fs::read_to_string(dir.join("summary.json"))
                    .map_err(|e| format!("{}: {e}", dir.display()))
            })
            .and_then(|t| serde_json::from_str(&t).map_err(|e| e.to_string()));
            let _ = std::fs::remove_dir_all(&dir);
            r
        }
    }
}

/// One run of an experiment: which variant, mode, swarm size and seed, and what it measured
/// (in the kind's order; None: not measured, e.g. a censored run's steps).
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    pub variant: String,
    pub mode: String,
    pub n: u32,
    pub seed: u64,
    pub metrics: Vec<(String, Option<f64>)>,
}

impl Row {
    pub fn new(variant: impl Into<String>, mode: impl Into<String>, n: u32, seed: u64) -> Row {
        Row {
            variant: variant.into(),
            mode: mode.into(),
            n,
            seed,
            metrics: Vec::new(),
        }
    }

    /// Adds a metric (a bool: 1 or 0).
    pub fn with(mut self, name: &str, v: impl Into<Metric>) -> Row {
        self.metrics.push((name.to_string(), v.into().0));
        self
    }

    fn to_json(&self) -> Value {
        let mut m = Map::new();
        m.insert("variant".into(), self.variant.clone().into());
        m.insert("mode".into(), self.mode.clone().into());
        m.insert("n".into(), self.n.into());
        m.insert("seed".into(), self.seed.into());
        for (k, v) in &self.metrics {
            m.insert(k.clone(), v.map_or(Value::Null, Value::from));
        }
        Value::Object(m)
    }
}

/// A metric's value: numbers, counts and flags as f64, a missing one as None.
pub struct Metric(Option<f64>);

impl From<f64> for Metric {
    fn from(v: f64) -> Self {
        Metric(v.is_finite().then_some(v))
    }
}
impl From<Option<f64>> for Metric {
    fn from(v: Option<f64>) -> Self {
        Metric(v.filter(|v| v.is_finite()))
    }
}
impl From<u64> for Metric {
    fn from(v: u64) -> Self {
        Metric(Some(v as f64))
    }
}
impl From<Option<u64>> for Metric {
    fn from(v: Option<u64>) -> Self {
        Metric(v.map(|v| v as f64))
    }
}
impl From<usize> for Metric {
    fn from(v: usize) -> Self {
        Metric(Some(v as f64))
    }
}
impl From<bool> for Metric {
    fn from(v: bool) -> Self {
        Metric(Some(if v { 1.0 } else { 0.0 }))
    }
}

/// What a kind hands back: its tables, its rows, what else results.json should hold, and
/// whether some run failed (exit 1).
#[derive(Debug, Default)]
pub struct Report {
    pub md: String,
    pub rows: Vec<Row>,
    pub json: Map<String, Value>,
    pub failed: bool,
}

/// Why the results could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {source}")]
    Csv { path: PathBuf, source: csv::Error },
}

/// The CSV's columns: variant, mode, N, seed, then every metric any row has, in the order
/// they first appear.
pub fn csv_header(rows: &[Row]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for (k, _) in rows.iter().flat_map(|r| &r.metrics) {
        if !names.contains(k) {
            names.push(k.clone());
        }
    }
    ["variant", "mode", "N", "seed"]
        .iter()
        .map(|s| s.to_string())
        .chain(names)
        .collect()
}

/// results.csv: one row per run; a metric a row does not have, or a missing value, is empty.
pub fn write_csv(rows: &[Row], path: &Path) -> Result<(), WriteError> {
    let err = |source| WriteError::Csv {
        path: path.to_path_buf(),
        source,
    };
    let header = csv_header(rows);
    let mut w = csv::Writer::from_path(path).map_err(err)?;
    w.write_record(&header).map_err(err)?;
    for r in rows {
        let mut rec = vec![
            r.variant.clone(),
            r.mode.clone(),
            r.n.to_string(),
            r.seed.to_string(),
        ];
        for k in &header[4..] {
            rec.push(
                r.metrics
                    .iter()
                    .find(|(m, _)| m == k)
                    .and_then(|(_, v)| *v)
                    .map_or(String::new(), |v| v.to_string()),
            );
        }
        w.write_record(&rec).map_err(err)?;
    }
    w.flush().map_err(|source| WriteError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes results.md, results.json (`kind`, `file`, `seeds`: every seed a row has, `rows`,
/// then the kind's own keys) and results.csv under `ctx.out`, and prints the tables.
pub fn write_results(ctx: &Context, kind: &str, r: &Report) -> Result<(), WriteError> {
    let io = |path: PathBuf| move |source| WriteError::Io { path, source };
    std::fs::create_dir_all(&ctx.out).map_err(io(ctx.out.clone()))?;
    let md_path = ctx.out.join(RESULTS_MD);
    std::fs::write(&md_path, &r.md).map_err(io(md_path.clone()))?;
    let mut seeds: Vec<u64> = r.rows.iter().map(|r| r.seed).collect();
    seeds.sort_unstable();
    seeds.dedup();
    let mut j = Map::new();
    j.insert("kind".into(), kind.into());
    j.insert("file".into(), ctx.name().into());
    j.insert("seeds".into(), seeds.into());
    j.insert(
        "rows".into(),
        Value::Array(r.rows.iter().map(Row::to_json).collect()),
    );
    for (k, v) in &r.json {
        j.insert(k.clone(), v.clone());
    }
    let json_path = ctx.out.join(RESULTS_JSON);
    let text = serde_json::to_string_pretty(&Value::Object(j)).expect("JSON of plain values");
    std::fs::write(&json_path, text).map_err(io(json_path.clone()))?;
    write_csv(&r.rows, &ctx.out.join(RESULTS_CSV))?;
    print!("{}", r.md);
    println!(
        "\nwritten: {}/{{{RESULTS_MD}, {RESULTS_JSON}, {RESULTS_CSV}}} ({} runs)",
        ctx.out.display(),
        r.rows.len()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_are_a_count_a_range_or_a_list_and_runs_takes_the_first_k() {
        assert_eq!(SeedSpec::Count(3).seeds(1, None).unwrap(), vec![1, 2, 3]);
        assert_eq!(SeedSpec::Count(2).seeds(7, None).unwrap(), vec![7, 8]);
        let r = SeedSpec::parse("9001..9004").unwrap();
        assert_eq!(r, SeedSpec::Range(9001, 9004));
        assert_eq!(r.seeds(1, None).unwrap(), vec![9001, 9002, 9003, 9004]);
        assert_eq!(r.seeds(1, Some(2)).unwrap(), vec![9001, 9002]);
        assert_eq!(r.seeds(1, Some(6)).unwrap().len(), 6);
        assert_eq!(SeedSpec::parse("5..=6").unwrap(), SeedSpec::Range(5, 6));
        let l = SeedSpec::parse("3, 5,8").unwrap();
        assert_eq!(l.seeds(1, None).unwrap(), vec![3, 5, 8]);
        assert_eq!(l.seeds(1, Some(2)).unwrap(), vec![3, 5]);
        assert!(matches!(
            l.seeds(1, Some(4)),
            Err(SeedError::TooFew { runs: 4, have: 3 })
        ));
        assert_eq!(SeedSpec::parse("9..3"), Err(SeedError::Reversed(9, 3)));
        assert!(matches!(
            SeedSpec::parse("a..3"),
            Err(SeedError::NotASeed(_))
        ));
        assert_eq!(SeedSpec::parse("4,4"), Err(SeedError::Repeated(4)));
    }

    #[test]
    fn a_files_seeds_key_reads_all_three_forms() {
        #[derive(Deserialize)]
        struct F {
            seeds: SeedSpec,
        }
        let f = |t: &str| toml::from_str::<F>(t).map(|f| f.seeds);
        assert_eq!(f("seeds = 10").unwrap(), SeedSpec::Count(10));
        assert_eq!(
            f("seeds = \"9001..9010\"").unwrap(),
            SeedSpec::Range(9001, 9010)
        );
        assert_eq!(f("seeds = [4, 2]").unwrap(), SeedSpec::List(vec![4, 2]));
        let e = f("seeds = 1.5").unwrap_err().to_string();
        assert!(e.contains("a range \"9001..9010\""), "{e}");
        assert!(f("seeds = -3").is_err());
        assert!(f("seeds = []").is_err());
    }

    #[test]
    fn the_csv_has_one_row_per_run_and_every_metric_a_column() {
        let rows = vec![
            Row::new("baseline, no rotation", "scenario 1", 9, 1)
                .with("formed", false)
                .with("K", None::<u64>),
            Row::new("ours", "scenario 1", 9, 2)
                .with("formed", true)
                .with("K", 41u64)
                .with("L", 35.5),
        ];
        assert_eq!(
            csv_header(&rows),
            ["variant", "mode", "N", "seed", "formed", "K", "L"]
        );
        let path = std::env::temp_dir().join(format!("sw-exp-csv-{}.csv", std::process::id()));
        write_csv(&rows, &path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let _ = std::fs::remove_file(&path);
        assert_eq!(
            text,
            "variant,mode,N,seed,formed,K,L\n\
             \"baseline, no rotation\",scenario 1,9,1,0,,\n\
             ours,scenario 1,9,2,1,41,35.5\n"
        );
    }
}
