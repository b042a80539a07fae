//! The fuzz harness (issues 14 and 37): mutated scenario files (from every file in configs/,
//! with structural mutations) and flag sets from a seeded generator (`e2e::fuzz`), each run
//! through `orchestrator up`, asserting for every case: exit 0 (its run left nothing in
//! /dev/shm under its own prefix and no process), or exit 2 with the key (or flag) and the
//! line it is written on named (the line that holds that key), a message of bounded length,
//! and nothing started; never a panic (exit 101), a signal, another exit code, or a hang past
//! the deadline.
//!
//! CI runs `FUZZ_CASES` cases (default 300) of seed `FUZZ_SEED` (default 14);
//! `scripts/fuzz.sh` runs thousands. The figures (cases by outcome) are printed.

use e2e::fuzz::{bases, case, Case};
use e2e::*;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Longest a case may take: an in-process run of a few ticks, or a processes run of a few
/// robots (start-up included), on a loaded 2-core machine.
const DEADLINE_INPROCESS: Duration = Duration::from_secs(30);
const DEADLINE_PROCESSES: Duration = Duration::from_secs(60);

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Outcome {
    Accepted,
    Refused,
    /// Failures:
    RefusedWithoutWhere,
    /// The error names a key and a line of the case's file, but that line does not hold
    /// that key (or the message echoes kilobytes of the input).
    WrongPlace,
    Panic,
    Signal,
    OtherExit,
    Hang,
    LeftBehind,
}

fn env_u64(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Longest error message accepted: a message names a key, a line, a range and a reason; it
/// never echoes a huge input back.
const MAX_MESSAGE_BYTES: usize = 2_000;

/// When the error is `FILE:LINE: `KEY` ...` for the case's own file and that file holds KEY,
/// whether LINE is KEY's line (the same parser's spans, but this catches a key reported at a
/// header or at another key's line); None when the error is not of that form.
fn points_at_its_key(err: &str, file: &Path) -> Option<bool> {
    let text = std::fs::read_to_string(file).ok()?;
    let name = format!("{}:", file.display());
    let rest = &err[err.find(&name)? + name.len()..];
    let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
    let line: usize = digits.parse().ok()?;
    let rest = rest[digits.len()..].strip_prefix(": `")?;
    let key = &rest[..rest.find('`')?];
    let want = swarm::key_lines::line_of(&text, key)?;
    Some(want == line)
}

/// Does the error say where: a key in backquotes with a `file:LINE` (or a flag), a syntax
/// error with its line, or a flag parser (clap) error that names the flag?
fn names_where(err: &str, file: Option<&Path>) -> bool {
    let has_line = |s: &str| {
        let mut found = false;
        for src in file
            .map(|f| f.display().to_string())
            .into_iter()
            .chain(["embedded default scenario".to_string()])
        {
            if let Some(i) = s.find(&format!("{src}:")) {
                found |= s[i + src.len() + 1..]
                    .chars()
                    .next()
                    .is_some_and(|c| c.is_ascii_digit());
            }
        }
        found
    };
    let backquoted_key = err.matches('`').count() >= 2;
    let flag = err.contains("'--") || err.contains(" --") || err.starts_with("error: --");
    // A key neither the file nor the default writes: its built-in default, said so.
    let built_in = err.contains("(not set there nor in the embedded default");
    (backquoted_key && (has_line(err) || flag || built_in))
        || (err.contains("not valid TOML") && has_line(err))
        || (err.contains("cannot read scenario file"))
        || (flag
            && (err.contains("invalid value")
                || err.contains("unexpected argument")
                || err.contains("cannot be used multiple times")))
}

fn run_case(c: &Case, dir: &Path) -> (Outcome, String) {
    let out = dir.join(format!("run-{}", c.index));
    let _ = std::fs::remove_dir_all(&out);
    let file = c.file.as_ref().map(|text| {
        let p = dir.join(format!("case-{}.toml", c.index));
        std::fs::write(&p, text).expect("write case file");
        p
    });
    let mut cmd = Command::new(orchestrator());
    cmd.arg("up").arg("--quiet").arg("--out").arg(&out);
    if let Some(p) = &file {
        cmd.arg("--scenario").arg(p);
    }
    cmd.arg("--executor")
        .arg(if c.processes {
            "processes"
        } else {
            "inprocess"
        })
        .args(&c.flags)
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    let mut child = cmd.spawn().expect("spawn orchestrator");
    let deadline = if c.processes {
        DEADLINE_PROCESSES
    } else {
        DEADLINE_INPROCESS
    };
    let t = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break Some(s);
        }
        if t.elapsed() > deadline {
            // Our own child, by its pid: Ctrl-C first (the clean shutdown), then SIGKILL.
            // SAFETY: signalling a child we spawned and have not reaped.
            unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
            std::thread::sleep(Duration::from_secs(5));
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let mut err = String::new();
    if let Some(mut e) = child.stderr.take() {
        use std::io::Read;
        let _ = e.read_to_string(&mut err);
    }
    let Some(status) = status else {
        return (Outcome::Hang, err);
    };
    use std::os::unix::process::ExitStatusExt;
    let outcome = match (status.code(), status.signal()) {
        (_, Some(_)) => Outcome::Signal,
        // A run that ended by itself, its mission accomplished (0) or not (3).
        (Some(0) | Some(3), _) => match left_behind(&out) {
            None => Outcome::Accepted,
            Some(what) => {
                err.push_str(&what);
                Outcome::LeftBehind
            }
        },
        (Some(2), _) => {
            if out.exists() {
                err.push_str("\n(a run folder was created for refused input)");
                Outcome::OtherExit
            } else if err.len() > MAX_MESSAGE_BYTES
                || file.as_deref().and_then(|f| points_at_its_key(&err, f)) == Some(false)
            {
                Outcome::WrongPlace
            } else if names_where(&err, file.as_deref()) {
                Outcome::Refused
            } else {
                Outcome::RefusedWithoutWhere
            }
        }
        (Some(101), _) => Outcome::Panic,
        _ => Outcome::OtherExit,
    };
    if matches!(outcome, Outcome::Accepted | Outcome::Refused) {
        let _ = std::fs::remove_dir_all(&out);
        if let Some(p) = &file {
            let _ = std::fs::remove_file(p);
        }
    }
    (outcome, err)
}

/// What an accepted run left: its /dev/shm files (its own prefix) or processes.
fn left_behind(out: &Path) -> Option<String> {
    let s = std::fs::read_to_string(out.join("summary.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&s).ok()?;
    let Some(run_id) = v["run_id"].as_str() else {
        return Some("\n(summary.json has no run_id)".into());
    };
    let prefix = swarm::transport::prefix_for(run_id);
    let shm: Vec<String> = run_shm_entries()
        .into_iter()
        .filter(|n| n.starts_with(&prefix))
        .collect();
    let procs = processes_mentioning(&prefix);
    (!shm.is_empty() || !procs.is_empty())
        .then(|| format!("\nrun {run_id} left /dev/shm {shm:?}, processes {procs:?}"))
}

#[test]
fn fuzzed_scenarios_and_flags_are_run_or_refused_with_where_never_crash() {
    let _g = serial();
    let cases = env_u64("FUZZ_CASES", 300);
    let seed = env_u64("FUZZ_SEED", 14);
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let bases = bases(&root.join("configs"));
    assert!(bases.len() >= 30, "{} files in configs/", bases.len());
    let dir = tmp_dir("fuzz");
    std::fs::create_dir_all(&dir).unwrap();
    let mut counts: BTreeMap<Outcome, u64> = BTreeMap::new();
    let mut by_executor: BTreeMap<(&str, Outcome), u64> = BTreeMap::new();
    let mut by_base: BTreeMap<(String, Outcome), u64> = BTreeMap::new();
    let mut failures = Vec::new();
    let t = Instant::now();
    for k in 0..cases {
        let c = case(seed, k, &bases);
        let (o, err) = run_case(&c, &dir);
        if std::env::var_os("FUZZ_SHOW").is_some() {
            println!(
                "case {k} {o:?} {:?}: {}",
                c.mutations,
                err.lines()
                    .next()
                    .unwrap_or("")
                    .chars()
                    .take(300)
                    .collect::<String>()
            );
        }
        *counts.entry(o).or_default() += 1;
        let ex = if c.processes {
            "processes"
        } else {
            "inprocess"
        };
        *by_executor.entry((ex, o)).or_default() += 1;
        *by_base.entry((c.base.clone(), o)).or_default() += 1;
        if !matches!(o, Outcome::Accepted | Outcome::Refused) {
            failures.push(format!(
                "case {k} (seed {seed}, from {}) {o:?}: {:?} flags {:?}\n  file kept in {}\n  {}",
                c.base,
                c.mutations,
                c.flags,
                dir.display(),
                err.lines()
                    .take(6)
                    .map(|l| l.chars().take(400).collect::<String>())
                    .collect::<Vec<_>>()
                    .join("\n  ")
            ));
        }
    }
    println!(
        "fuzz: {cases} cases of seed {seed} in {:.1} s: {counts:?}",
        t.elapsed().as_secs_f64()
    );
    println!("fuzz by executor: {by_executor:?}");
    println!("fuzz by base file: {by_base:?}");
    assert!(
        failures.is_empty(),
        "{} of {cases} cases failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
    let _ = std::fs::remove_dir_all(&dir);
}
