//! `orchestrator experiment` for every kind (search, formation, hunt, CBCA), with the real
//! binary: it writes only under `--out` (nothing in the working directory, nothing beside the
//! experiment file), results.md / results.json / results.csv with one CSV row per run, and
//! `--seeds` or a file's `seeds` (a range or a list) choose the seeds of every row.

use e2e::*;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn configs() -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../configs")
        .canonicalize()
        .unwrap()
        .display()
        .to_string()
}

/// A test's folders: `work` (the working directory, empty), `files` (the experiment file)
/// and `out`, which the experiment must be the only one to write into.
struct Dirs {
    root: PathBuf,
    work: PathBuf,
    files: PathBuf,
    out: PathBuf,
}

fn dirs(name: &str) -> Dirs {
    let root = tmp_dir(name);
    let d = Dirs {
        work: root.join("work"),
        files: root.join("files"),
        out: root.join("out"),
        root,
    };
    std::fs::create_dir_all(&d.work).unwrap();
    std::fs::create_dir_all(&d.files).unwrap();
    d
}

/// Writes the experiment file `name` (a tiny experiment: `body`) and runs it from `work`.
fn experiment(d: &Dirs, name: &str, body: &str, args: &[&str]) -> Output {
    let file = d.files.join(name);
    std::fs::write(&file, body).unwrap();
    Command::new(orchestrator())
        .current_dir(&d.work)
        .arg("experiment")
        .arg(&file)
        .arg("--quiet")
        .args(args)
        .output()
        .unwrap()
}

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// results.csv's rows (header first) and results.json's `rows`.
fn results(out: &Path) -> (Vec<csv::StringRecord>, Vec<serde_json::Value>) {
    let mut r = csv::Reader::from_path(out.join("results.csv")).unwrap();
    let mut rows = vec![r.headers().unwrap().clone()];
    rows.extend(r.records().map(|x| x.unwrap()));
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    (rows, j["rows"].as_array().unwrap().clone())
}

/// The seeds of the CSV's rows.
fn seeds_of(csv: &[csv::StringRecord]) -> BTreeSet<u64> {
    assert_eq!(&csv[0][3], "seed");
    csv[1..].iter().map(|r| r[3].parse().unwrap()).collect()
}

fn search(seeds: &str) -> String {
    format!(
        "scenario = \"{}/search.toml\"\nmodes = [\"BT\"]\nrobots = [20]\nseeds = {seeds}\nmax_ticks = 3000\n",
        configs()
    )
}

fn formation(table: &str, seeds: &str) -> String {
    format!(
        "kind = \"formation\"\ntable = \"{table}\"\nscenario = \"{}/formation.toml\"\nseeds = {seeds}\nplacements = 1\n",
        configs()
    )
}

fn hunt() -> String {
    format!(
        "kind = \"hunt\"\nscenario = \"{}/hunt-example-3a.toml\"\nseeds = 1\n\
         sweep_robots = [6]\nsweep_robots_evaders = 2\nsweep_evaders = [2]\nsweep_evaders_robots = 6\n\
         variant_seeds = 1\nauctions = [\"improved\"]\nvariants = [{{ name = \"lossless\" }}]\n",
        configs()
    )
}

fn cbca() -> String {
    format!(
        "kind = \"cbca\"\nexample1 = \"{0}/hunt-cbca.toml\"\nexample2 = \"{0}/hunt-cbca-example2-hunt.toml\"\n\
         seeds = 1\nsweep_robots = [6]\nsweep_robots_evaders = 2\nsweep_evaders = [2]\nsweep_evaders_robots = 6\n\
         losses = [0.0]\nloss_point = [6, 2]\nloss_max_delay = 1\nutility_horizon = 2.0\nutility_step = 0.5\n\
         variant_seeds = 1\nvariants = [{{ name = \"lossless\" }}]\n",
        configs()
    )
}

/// Issue 39: the formation experiment wrote ./results/formation-table1.{md,json} into the
/// working directory whatever `--out` said, and the hunt wrote no results.json. Each kind,
/// run from an empty working directory, writes only under `--out`: the three results files
/// (and its charts), one CSV row per run, the same rows as results.json.
#[test]
fn every_kind_writes_only_under_out_with_one_csv_row_per_run() {
    let _g = serial();
    // (kind, file, runs: every scenario run or kernel run of the tiny experiment).
    let cases: [(&str, String, usize); 4] = [
        // 1 mode x 1 N x 2 seeds.
        ("search", search("2"), 2),
        // 2 algorithms x (1 orientation + 2 seeds).
        ("formation", formation("table1", "2"), 6),
        // Example 3-A, 2 sweep points x 2 auctions, 1 live run.
        ("hunt", hunt(), 6),
        // 2 hunt-world examples, 2 sweep points x 5 methods, the loss sweep's 2 setups, 1
        // variant run.
        ("cbca", cbca(), 15),
    ];
    for (kind, body, runs) in cases {
        let d = dirs(&format!("exp-{kind}"));
        let out = d.out.to_str().unwrap().to_string();
        let o = experiment(&d, "x.toml", &body, &["--out", &out]);
        assert!(o.status.success(), "{kind}: {}", stderr(&o));
        assert_eq!(
            entries(&d.work),
            Vec::<String>::new(),
            "{kind}: working dir"
        );
        assert_eq!(entries(&d.files), ["x.toml"], "{kind}: beside the file");
        let have = entries(&d.out);
        for f in ["results.md", "results.json", "results.csv"] {
            assert!(have.contains(&f.to_string()), "{kind}: no {f} in {have:?}");
        }
        let (csv, json) = results(&d.out);
        assert_eq!(csv.len() - 1, runs, "{kind}: CSV rows");
        assert_eq!(json.len(), runs, "{kind}: results.json rows");
        assert_eq!(
            &csv[0].iter().take(4).collect::<Vec<_>>(),
            &["variant", "mode", "N", "seed"]
        );
        for (c, j) in csv[1..].iter().zip(&json) {
            assert_eq!(
                c[3].parse::<u64>().unwrap(),
                j["seed"].as_u64().unwrap(),
                "{kind}"
            );
            assert_eq!(&c[1], j["mode"].as_str().unwrap(), "{kind}");
        }
        std::fs::remove_dir_all(&d.root).ok();
    }
}

/// Without `--out` the results go to runs/experiments/<file stem>-<id> under the working
/// directory, and nowhere else.
#[test]
fn without_out_the_results_go_under_runs_experiments() {
    let _g = serial();
    let d = dirs("exp-default-out");
    let o = experiment(&d, "grid.toml", &search("1"), &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(entries(&d.work), ["runs"]);
    assert_eq!(entries(&d.work.join("runs")), ["experiments"]);
    let runs = entries(&d.work.join("runs/experiments"));
    assert_eq!(runs.len(), 1, "{runs:?}");
    assert!(runs[0].starts_with("grid-"), "{runs:?}");
    let out = d.work.join("runs/experiments").join(&runs[0]);
    let (csv, _) = results(&out);
    assert_eq!(csv.len() - 1, 1);
    std::fs::remove_dir_all(&d.root).ok();
}

/// `--seeds` (a range, both ends included, or a list) and a file's `seeds` (a range or a
/// list) are the rows' seeds, for a search grid and a formation table alike.
#[test]
fn the_seeds_flag_and_key_choose_every_rows_seed() {
    let _g = serial();
    let d = dirs("exp-seeds");
    let out = d.out.to_str().unwrap().to_string();
    let set = |v: &[u64]| v.iter().copied().collect::<BTreeSet<u64>>();
    let cases: [(String, Vec<&str>, Vec<u64>); 5] = [
        (
            search("2"),
            vec!["--seeds", "9001..9003"],
            vec![9001, 9002, 9003],
        ),
        (search("2"), vec!["--seeds", "11,17"], vec![11, 17]),
        (search("[5, 8]"), vec![], vec![5, 8]),
        (search("\"40..41\""), vec!["--runs", "1"], vec![40]),
        (
            formation("one-shot", "2"),
            vec!["--seeds", "9001..9002"],
            vec![9001, 9002],
        ),
    ];
    for (body, args, want) in cases {
        let mut a = vec!["--out", out.as_str()];
        a.extend(&args);
        let o = experiment(&d, "x.toml", &body, &a);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        let (csv, _) = results(&d.out);
        assert_eq!(seeds_of(&csv), set(&want), "{args:?}\n{body}");
        // Every seed has its run(s): one a seed for the grid, two (per-step, one-shot) for
        // the formation.
        let per_seed = if body.contains("formation") { 2 } else { 1 };
        assert_eq!(csv.len() - 1, want.len() * per_seed, "{args:?}");
        std::fs::remove_dir_all(&d.out).unwrap();
    }
    std::fs::remove_dir_all(&d.root).ok();
}

/// Bad seeds stop the experiment before it starts: exit 2, the flag or the file, line and
/// key named with the allowed forms, and no results folder made.
#[test]
fn bad_seeds_exit_2_naming_the_flag_or_the_key_and_write_nothing() {
    let _g = serial();
    let d = dirs("exp-bad-seeds");
    let out = d.out.to_str().unwrap().to_string();
    let o = experiment(
        &d,
        "x.toml",
        &search("2"),
        &["--out", &out, "--seeds", "9..3"],
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--seeds"), "{}", stderr(&o));
    let o = experiment(&d, "x.toml", &search("\"many\""), &["--out", &out]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("x.toml:4:") && e.contains("seeds") && e.contains("A..B"),
        "{e}"
    );
    let o = experiment(&d, "x.toml", &search("[3, 3]"), &["--out", &out]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("seed 3 is given twice"),
        "{}",
        stderr(&o)
    );
    assert!(!d.out.exists(), "bad input made {}", d.out.display());
    assert_eq!(entries(&d.work), Vec::<String>::new());
    std::fs::remove_dir_all(&d.root).ok();
}
