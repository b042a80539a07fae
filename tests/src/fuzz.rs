//! A seeded generator of hostile `orchestrator up` inputs: mutated scenario files and flag
//! sets (no cargo-fuzz: plain Rust over a ChaCha stream, so case k of seed s is the same case
//! on every machine).
//!
//! A case starts from one of the files in configs/ (every one: scenarios and experiment
//! files, which `up` must send to `orchestrator experiment`), written out whole or only in
//! part, and applies a few mutations: a leaf replaced by a hostile value (NaN, inf, range
//! edges, subnormals, a wrong type, unicode, a 1 MB string), an unknown or removed key, and
//! the structural ones of [`crate::fuzz_mutations`] (a huge list, another behaviour's
//! section, a key in the wrong table, a unicode key, a key or table written twice, an integer
//! beyond 64 bits, a truncated file); then draws flags, some hostile. Every case runs a short,
//! small run (`--max-ticks 3` unless a flag mutation says otherwise, a few robots) so that what
//! is accepted finishes in well under a second in-process.

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::Path;
use toml::{Table, Value};

use crate::fuzz_mutations as m;

/// One file a case starts from.
#[derive(Debug, Clone)]
pub struct Base {
    /// Its path under configs/.
    pub name: String,
    pub text: String,
    /// Its `run.robots` when it sets one (a case may then leave `--robots` out).
    pub robots: Option<i64>,
}

/// Largest `run.robots` of a base that a case may run without `--robots` (a hunt's table
/// fixes its count; 16 robots run 3 ticks in well under a second).
pub const OWN_ROBOTS_AT_MOST: i64 = 20;

/// Every *.toml file under `configs` (sorted, so that case k is the same case everywhere).
pub fn bases(configs: &Path) -> Vec<Base> {
    let mut files = Vec::new();
    let mut dirs = vec![configs.to_path_buf()];
    while let Some(d) = dirs.pop() {
        for e in std::fs::read_dir(&d).expect("read configs").flatten() {
            let p = e.path();
            if p.is_dir() {
                dirs.push(p);
            } else if p.extension().is_some_and(|x| x == "toml") {
                files.push(p);
            }
        }
    }
    files.sort();
    files
        .into_iter()
        .map(|p| {
            let text = std::fs::read_to_string(&p).expect("read a config");
            let robots = text
                .parse::<Table>()
                .ok()
                .and_then(|t| t.get("run")?.get("robots")?.as_integer());
            Base {
                name: p.strip_prefix(configs).unwrap_or(&p).display().to_string(),
                text,
                robots,
            }
        })
        .collect()
}

/// Probability that an accepted-looking case runs with real processes (the rest in-process).
pub const PROCESSES_SHARE: f64 = 0.04;

/// One generated input.
#[derive(Debug, Clone)]
pub struct Case {
    pub index: u64,
    /// The configs/ file it started from.
    pub base: String,
    /// The scenario file's text (None: no --scenario).
    pub file: Option<String>,
    /// Flags after `up --quiet --out DIR [--scenario FILE]`.
    pub flags: Vec<String>,
    /// What was done, for the report of a failing case.
    pub mutations: Vec<String>,
    /// Runs with `--executor processes`.
    pub processes: bool,
}

/// Share of mild cases: plausible changes only (numbers scaled, no hostile flag), so that
/// enough cases are accepted and run.
pub const MILD_SHARE: f64 = 0.35;

/// Hostile replacements for a leaf (`mild`: only the plausible ones).
fn hostile(rng: &mut ChaCha8Rng, old: &Value, mild: bool) -> (Value, String) {
    let float = |x: f64, name: &str| (Value::Float(x), name.to_string());
    let int = |x: i64, name: &str| (Value::Integer(x), name.to_string());
    let kind = if mild { 14 } else { rng.gen_range(0..26) };
    match kind {
        0 => float(f64::NAN, "nan"),
        1 => float(f64::INFINITY, "inf"),
        2 => float(f64::NEG_INFINITY, "-inf"),
        3 => int(-1, "-1"),
        4 => int(0, "0"),
        5 => float(0.0, "0.0"),
        6 => float(1e300, "1e300"),
        7 => float(1e-9, "1e-9"),
        8 => int(i64::MAX, "i64::MAX"),
        9 => (Value::Array(Vec::new()), "[]".into()),
        10 => (Value::String("x".into()), "\"x\"".into()),
        11 => (Value::Boolean(true), "true".into()),
        12 => (Value::Table(Table::new()), "{}".into()),
        13 => float(-1.5, "-1.5"),
        // A plausible change: the old number scaled (often still valid).
        14 => match old {
            Value::Float(x) => float(x * rng.gen_range(0.0..3.0), "scaled"),
            Value::Integer(i) => int(i / 2, "halved"),
            v => (v.clone(), "same".into()),
        },
        // Range edges and subnormals.
        15 => float(5e-324, "5e-324 (subnormal)"),
        16 => float(2.2e-308, "2.2e-308 (subnormal)"),
        17 => float(f64::MAX, "f64::MAX"),
        18 => float(-0.0, "-0.0"),
        19 => int(i64::MIN, "i64::MIN"),
        20 => int(u32::MAX as i64 + 1, "u32::MAX + 1"),
        21 => int(4097, "MAX_ROBOTS + 1"),
        // Strings: unicode, and one of 1 MB.
        22 => {
            let u = *m::UNICODE.choose(rng).unwrap();
            (Value::String(u.into()), format!("{u:?}"))
        }
        23 => (Value::String(m::huge_string()), "a 1 MB string".into()),
        24 => match old {
            Value::Float(x) => float(x * (1.0 + f64::EPSILON), "x (1 + eps)"),
            Value::Integer(i) => int(i.saturating_add(1), "+1"),
            v => (v.clone(), "same".into()),
        },
        _ => match old {
            Value::Array(a) if !a.is_empty() => {
                let mut a = a.clone();
                a.truncate(rng.gen_range(0..a.len()));
                (Value::Array(a), "shortened array".into())
            }
            Value::Integer(i) => int(i.saturating_mul(1000), "x1000"),
            Value::Float(x) => float(-x, "negated"),
            v => (v.clone(), "same".into()),
        },
    }
}

/// Every leaf path of `t` (into tables and arrays), as steps.
#[derive(Debug, Clone)]
enum Step {
    Key(String),
    Index(usize),
}

fn leaves(v: &Value, path: &mut Vec<Step>, out: &mut Vec<Vec<Step>>) {
    match v {
        Value::Table(t) => {
            for (k, c) in t {
                path.push(Step::Key(k.clone()));
                leaves(c, path, out);
                path.pop();
            }
        }
        Value::Array(a) if !a.is_empty() => {
            out.push(path.clone());
            for (i, c) in a.iter().enumerate() {
                path.push(Step::Index(i));
                leaves(c, path, out);
                path.pop();
            }
        }
        _ => out.push(path.clone()),
    }
}

/// A leaf drawn section first (each top-level section equally likely), so that the long
/// obstacle lists do not take most of the draws.
fn pick<'a>(rng: &mut ChaCha8Rng, all: &'a [Vec<Step>]) -> Option<&'a Vec<Step>> {
    let mut sections: Vec<&str> = all
        .iter()
        .filter_map(|p| match p.first() {
            Some(Step::Key(k)) => Some(k.as_str()),
            _ => None,
        })
        .collect();
    sections.dedup();
    let s = *sections.choose(rng)?;
    let in_section: Vec<&Vec<Step>> = all
        .iter()
        .filter(|p| matches!(p.first(), Some(Step::Key(k)) if k == s))
        .collect();
    in_section.choose(rng).copied()
}

fn at<'a>(v: &'a mut Value, path: &[Step]) -> Option<&'a mut Value> {
    let mut cur = v;
    for s in path {
        cur = match (s, cur) {
            (Step::Key(k), Value::Table(t)) => t.get_mut(k)?,
            (Step::Index(i), Value::Array(a)) => a.get_mut(*i)?,
            _ => return None,
        };
    }
    Some(cur)
}

fn show(path: &[Step]) -> String {
    let mut s = String::new();
    for p in path {
        match p {
            Step::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(k);
            }
            Step::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

/// Keeps only the sections of `full` that `touched` names (a partial file, as users write).
fn partial(full: &Table, touched: &[String]) -> Table {
    let mut t = Table::new();
    for (k, v) in full {
        if touched
            .iter()
            .any(|p| p == k || p.starts_with(&format!("{k}.")))
        {
            t.insert(k.clone(), v.clone());
        }
    }
    t
}

/// Hostile and ordinary flag values.
fn flags(
    rng: &mut ChaCha8Rng,
    mild: bool,
    robots_flag: bool,
    out: &mut Vec<String>,
    notes: &mut Vec<String>,
) {
    let mut push = |f: &str, v: String, notes: &mut Vec<String>| {
        notes.push(format!("{f} {v}"));
        out.push(f.to_string());
        out.push(v);
    };
    // Small runs unless a mutation says otherwise.
    let robots = match if mild { 19 } else { rng.gen_range(0..20) } {
        0 => "0".to_string(),
        1 => "4097".to_string(),
        2 => "-1".to_string(),
        3 => "many".to_string(),
        _ => rng.gen_range(1..=6).to_string(),
    };
    if robots_flag {
        push("--robots", robots, notes);
    }
    let ticks = match if mild { 19 } else { rng.gen_range(0..20) } {
        0 => "0".to_string(),
        1 => "-3".to_string(),
        _ => rng.gen_range(1..=3).to_string(),
    };
    push("--max-ticks", ticks, notes);
    for _ in 0..if mild { 0 } else { rng.gen_range(0..3) } {
        let (f, v): (&str, String) = match rng.gen_range(0..14) {
            0 => (
                "--seed",
                ["18446744073709551615", "9223372036854775808", "0", "-1"]
                    .choose(rng)
                    .unwrap()
                    .to_string(),
            ),
            1 => (
                "--comm-radius",
                ["nan", "-3", "1e300", "0", "50"]
                    .choose(rng)
                    .unwrap()
                    .to_string(),
            ),
            2 => (
                "--loss",
                ["1.5", "nan", "-0.1", "0.3", "1"]
                    .choose(rng)
                    .unwrap()
                    .to_string(),
            ),
            3 => (
                "--delay",
                ["0", "2", "1001", "-1", "4294967296"]
                    .choose(rng)
                    .unwrap()
                    .to_string(),
            ),
            4 => (
                "--tick-hz",
                ["1e-300", "0", "1e9", "-5", "nan", "200"]
                    .choose(rng)
                    .unwrap()
                    .to_string(),
            ),
            5 => (
                "--chaos",
                ["-3", "nan", "1000", "50"].choose(rng).unwrap().to_string(),
            ),
            6 => (
                "--chaos-at",
                [
                    "1:0",
                    "2:99",
                    "x",
                    "1:0,2:1",
                    ":",
                    "9223372036854775808:0",
                    "18446744073709551615:0",
                    "100000001:0",
                    "1:18446744073709551615",
                ]
                .choose(rng)
                .unwrap()
                .to_string(),
            ),
            7 => (
                "--kill-fraction",
                ["2", "nan", "0.5", "-0.1"].choose(rng).unwrap().to_string(),
            ),
            8 => (
                "--mode",
                ["XT", "BA", "SE", "bt"].choose(rng).unwrap().to_string(),
            ),
            9 => (
                "--on-fault",
                ["restart", "drop", "ignore"]
                    .choose(rng)
                    .unwrap()
                    .to_string(),
            ),
            10 => (
                "--max-restarts",
                ["0", "5", "-1", "99999999999"]
                    .choose(rng)
                    .unwrap()
                    .to_string(),
            ),
            11 => ("--executor", ["threads"].choose(rng).unwrap().to_string()),
            12 => ("--robots", ["0", "3"].choose(rng).unwrap().to_string()),
            _ => ("--bogus-flag", "1".to_string()),
        };
        push(f, v, notes);
    }
}

/// Case `index` of the stream `seed`; `bases` are the files mutations start from.
pub fn case(seed: u64, index: u64, bases: &[Base]) -> Case {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(index);
    let mut mutations = Vec::new();
    let base = &bases[rng.gen_range(0..bases.len())];
    let mut doc = Value::Table(base.text.parse::<Table>().expect("base scenario parses"));
    let mut touched: Vec<String> = Vec::new();
    let mild = rng.gen_bool(MILD_SHARE);
    if mild {
        mutations.push("mild".into());
    }
    let file = if rng.gen_bool(0.1) {
        None
    } else {
        for _ in 0..rng.gen_range(1..=3) {
            let mut all = Vec::new();
            leaves(&doc, &mut Vec::new(), &mut all);
            let Value::Table(table) = &mut doc else {
                unreachable!()
            };
            match if mild { 9 } else { rng.gen_range(0..14) } {
                // Unknown key, in a random table.
                0 => {
                    let tables: Vec<&Vec<Step>> = all.iter().filter(|p| p.len() >= 2).collect();
                    if let Some(p) = tables.choose(&mut rng) {
                        let parent = &p[..p.len() - 1];
                        if let Some(Value::Table(t)) = at(&mut doc, parent) {
                            t.insert("unknwn_key".into(), Value::Integer(1));
                            let name = show(parent);
                            mutations.push(format!("unknown key in {name}"));
                            touched.push(name);
                        }
                    }
                }
                // Removed key.
                1 => {
                    if let Some(p) = pick(&mut rng, &all) {
                        if let (Some(Step::Key(k)), parent) = (p.last(), &p[..p.len() - 1]) {
                            if let Some(Value::Table(t)) = at(&mut doc, parent) {
                                t.remove(k);
                                mutations.push(format!("removed {}", show(p)));
                                touched.push(show(p));
                            }
                        }
                    }
                }
                // Structural mutations.
                10 => {
                    mutations.push(m::huge_list(&mut rng, table));
                    touched.extend(["arena".to_string()]);
                    touched.extend(table.keys().cloned());
                }
                11 => {
                    let what = m::foreign_section(&mut rng, table);
                    touched.extend(table.keys().cloned());
                    mutations.push(what);
                }
                12 => {
                    mutations.push(m::wrong_table(&mut rng, table));
                    touched.extend(table.keys().cloned());
                }
                13 => {
                    mutations.push(m::unicode_key(&mut rng, table));
                    touched.extend(table.keys().cloned());
                }
                // A hostile value.
                _ => {
                    if let Some(p) = pick(&mut rng, &all) {
                        if let Some(v) = at(&mut doc, p) {
                            let (new, name) = hostile(&mut rng, v, mild);
                            *v = new;
                            mutations.push(format!("{} = {name}", show(p)));
                            touched.push(show(p));
                        }
                    }
                }
            }
        }
        let Value::Table(full) = &doc else {
            unreachable!()
        };
        let table = if rng.gen_bool(0.5) {
            partial(full, &touched)
        } else {
            full.clone()
        };
        let mut text = toml::to_string(&table).unwrap_or_default();
        if !mild && rng.gen_bool(0.12) {
            if let Some(what) = m::text_mutation(&mut rng, &mut text) {
                mutations.push(what);
            }
        }
        if !mild && rng.gen_bool(0.08) {
            let mut cut = rng.gen_range(0..=text.len());
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            text.truncate(cut);
            mutations.push(format!("truncated at byte {cut}"));
        }
        Some(text)
    };
    let own_robots = base.robots.is_some_and(|r| r <= OWN_ROBOTS_AT_MOST) && rng.gen_bool(0.5);
    let mut f = Vec::new();
    flags(&mut rng, mild, !own_robots, &mut f, &mut mutations);
    let processes = rng.gen_bool(PROCESSES_SHARE);
    Case {
        index,
        base: base.name.clone(),
        file,
        flags: f,
        mutations,
        processes,
    }
}
