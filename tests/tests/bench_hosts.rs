//! `orchestrator bench tick`'s rows across hosts (issue 41) at a tiny size: 8 robots over 2
//! network namespaces, 30 ticks, one run a figure, without and with a netem delay. As root a
//! row with numbers is printed (the netem row has numbers, or says netem is unavailable with
//! tc's words), and no namespace of the bench and nothing of its runs (named in its JSON) in
//! /dev/shm is left behind. Not root: the bench says in one line why the rows are skipped and
//! succeeds. No timings are judged.

use e2e::*;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// How long the bench may take before the test stops it (a guard against a hang, not a
/// judgement of its speed).
const PATIENCE: Duration = Duration::from_secs(600);

/// The bench (its pid and output), its JSON written to `json`.
fn bench_hosts(json: &Path) -> (u32, Output) {
    let child = Command::new(orchestrator())
        .args(["bench", "tick", "--json"])
        .arg(json)
        .args([
            "--hosts-only",
            "--robots",
            "8",
            "--ticks",
            "30",
            "--hosts",
            "2",
            "--netem-ms",
            "0,0.5",
            "--hosts-runs",
            "1",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn bench tick");
    let pid = child.id();
    let t = Instant::now();
    while pid_alive(pid as i32) && t.elapsed() < PATIENCE {
        std::thread::sleep(Duration::from_millis(50));
    }
    if pid_alive(pid as i32) {
        // SAFETY: a child of this test; its Ctrl-C stops the runs and removes the namespaces.
        unsafe { libc::kill(pid as i32, libc::SIGINT) };
    }
    (pid, child.wait_with_output().expect("bench output"))
}

/// The namespaces of the bench with this pid still listed by `ip netns`.
fn namespaces_of(pid: u32) -> Vec<String> {
    let o = Command::new("ip").args(["netns", "list"]).output().unwrap();
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .filter(|n| n.starts_with(&format!("swb{pid}")))
        .map(String::from)
        .collect()
}

/// The row's fields after its head (`robots ns netem ticks runs |`), if its head is these.
fn row<'a>(out: &'a str, netem: &str) -> Option<&'a str> {
    out.lines().find_map(|l| {
        let (head, rest) = l.split_once('|')?;
        let h: Vec<&str> = head.split_whitespace().collect();
        (h.len() == 5 && h[0] == "8" && h[1] == "2" && h[2] == netem && h[4] == "1").then_some(rest)
    })
}

/// The four numbers (rtt, one host, across, target), "yes"/"no" and the recording's word of
/// a measured row.
fn numbers(rest: &str) -> Option<(Vec<f64>, String, String)> {
    let f: Vec<&str> = rest.split('|').map(str::trim).collect();
    if f.len() != 6 {
        return None;
    }
    let nums: Vec<f64> = f[..4].iter().filter_map(|s| s.parse().ok()).collect();
    (nums.len() == 4 && nums.iter().all(|x| x.is_finite()))
        .then(|| (nums, f[4].to_string(), f[5].to_string()))
}

#[test]
fn bench_tick_rows_across_hosts_print_numbers_and_leave_nothing() {
    let _g = serial();
    // SAFETY: geteuid cannot fail.
    if unsafe { libc::geteuid() } != 0 {
        let (_, o) = bench_hosts(&tmp_dir("bench-hosts.json"));
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success(), "{out}{}", stderr(&o));
        assert!(
            out.lines()
                .any(|l| l.starts_with("tick across hosts: skipped: ") && l.contains("root")),
            "{out}"
        );
        eprintln!("skipped: the rows across hosts need root (network namespaces); checked the skip line only");
        return;
    }
    let json = tmp_dir("bench-hosts.json");
    let (pid, o) = bench_hosts(&json);
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(o.status.success(), "{out}{}", stderr(&o));
    let plain = row(&out, "0").unwrap_or_else(|| panic!("no row for 8 robots, 2 ns:\n{out}"));
    let (_, met, recording) =
        numbers(plain).unwrap_or_else(|| panic!("the row has no numbers: {plain}\n{out}"));
    assert!(met == "yes" || met == "no", "{plain}");
    assert_eq!(recording, "same", "{plain}");
    let delayed = row(&out, "0.5").unwrap_or_else(|| panic!("no netem row:\n{out}"));
    assert!(
        numbers(delayed).is_some() || delayed.trim().starts_with("netem unavailable: "),
        "{delayed}"
    );
    assert_eq!(namespaces_of(pid), Vec::<String>::new(), "namespaces left");
    // Each run's files: the world's under its id's prefix, host h1's proxy's under
    // `<id>@h1`'s (the JSON names the runs; other runs on the machine are not judged).
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("the bench's JSON")).unwrap();
    let _ = std::fs::remove_file(&json);
    let rows = report["hosts"]["rows"]
        .as_array()
        .expect("rows in the JSON");
    let ids: Vec<&str> = rows
        .iter()
        .flat_map(|r| r["run_ids"].as_array().unwrap())
        .map(|id| id.as_str().unwrap())
        .collect();
    assert!(ids.len() >= 2, "{report}");
    for id in ids {
        assert_eq!(shm_of_run(id), Vec::<String>::new(), "left by run {id}");
        assert_eq!(
            shm_of_run(&format!("{id}@h1")),
            Vec::<String>::new(),
            "left by run {id}'s proxy"
        );
    }
}
