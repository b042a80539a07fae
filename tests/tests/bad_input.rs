//! Bad input: a clear error naming the flag or file and key and the allowed range, exit code 2,
//! no process started and nothing left behind.

use e2e::*;

fn expect_rejected(args: &[&str], must_name: &[&str]) {
    let out = tmp_dir("bad");
    // The run's own id: a refused run must create nothing under its prefix (other runs may be
    // on the machine, so the test looks at this run's files only).
    let id = own_run_id("bad");
    let o = up_as(args, &out, Some(&id));
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "args {args:?}: {err}");
    for m in must_name {
        assert!(
            err.contains(m),
            "error for {args:?} should name {m:?}: {err}"
        );
    }
    assert!(!out.exists(), "no run folder for rejected input");
    let left = shm_of_run(&id);
    assert!(left.is_empty(), "nothing created in /dev/shm: {left:?}");
}

#[test]
fn bad_flags_are_rejected_with_the_allowed_range() {
    let _g = serial();
    expect_rejected(&["--robots", "0"], &["--robots", "run.robots", "1..=4096"]);
    expect_rejected(&["--loss", "1.5"], &["--loss", "radio.loss", "[0, 1]"]);
    expect_rejected(
        &["--comm-radius", "-3"],
        &["--comm-radius", "radio.comm_radius"],
    );
    expect_rejected(&["--executor", "threads"], &["processes", "inprocess"]);
    expect_rejected(&["--robots", "many"], &["--robots"]);
    expect_rejected(
        &["--chaos", "-3"],
        &["--chaos", "faults.chaos_rate", "[0, 100]"],
    );
    expect_rejected(
        &["--robots", "3", "--chaos-at", "10:99"],
        &["--chaos-at", "robot 99", "0..=2"],
    );
    expect_rejected(
        &["--kill-fraction", "2"],
        &["--kill-fraction", "faults.kill_fraction", "[0, 1]"],
    );
    expect_rejected(&["--mode", "XT"], &["BT", "BE", "BA", "ST", "SE", "SA"]);
}

#[test]
fn bad_scenario_files_name_the_file_and_key() {
    let _g = serial();
    let dir = tmp_dir("bad-files");
    std::fs::create_dir_all(&dir).unwrap();
    let missing = dir.join("nope.toml");
    expect_rejected(
        &["--scenario", missing.to_str().unwrap()],
        &["nope.toml", "cannot read"],
    );
    let unknown = dir.join("unknown.toml");
    std::fs::write(&unknown, "[radio]\ncomm_radios = 10.0\n").unwrap();
    expect_rejected(
        &["--scenario", unknown.to_str().unwrap()],
        &["unknown.toml", "comm_radios"],
    );
    let range = dir.join("range.toml");
    std::fs::write(&range, "[robot]\nv_max = -1.0\n").unwrap();
    expect_rejected(
        &["--scenario", range.to_str().unwrap()],
        &["range.toml", "robot.v_max"],
    );
    let kind = dir.join("behaviour.toml");
    std::fs::write(&kind, "[run]\nbehaviour = \"dance\"\n").unwrap();
    expect_rejected(
        &["--scenario", kind.to_str().unwrap()],
        &["behaviour.toml", "run.behaviour", "roam"],
    );
}

/// Every u64 is a seed (issue 14 item 4: TOML integers are i64, and `--seed 2^63` panicked
/// with `scenario serialises: OutOfRange`). u64::MAX goes through the CLI, the resolved
/// scenario.toml the world reads, and back out in the summary.
#[test]
fn a_seed_above_two_to_the_63_runs() {
    let _g = serial();
    let out = tmp_dir("seed-max");
    let max = u64::MAX.to_string();
    let o = up(
        &[
            "--robots",
            "2",
            "--max-ticks",
            "5",
            "--scenario",
            roam(),
            "--seed",
            &max,
        ],
        &out,
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let resolved = std::fs::read_to_string(out.join("scenario.toml")).unwrap();
    let sc = swarm::Scenario::parse(&resolved, "resolved").unwrap();
    assert_eq!(sc.run.seed, u64::MAX);
    assert_eq!(summary(&out)["seed"].as_u64(), Some(u64::MAX));
    assert_left_nothing(&out);
    // A negative seed is bad input (exit 2), not a panic.
    expect_rejected(&["--seed", "-1"], &["--seed"]);
}

/// A run folder that cannot be written is bad input like any other: exit 2, the error names
/// --out, nothing started (issue 14 item 10; it exited 1).
#[test]
fn an_unwritable_out_folder_exits_2() {
    let _g = serial();
    let dir = tmp_dir("bad-out");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("a-file");
    std::fs::write(&file, "x").unwrap();
    for out in [
        file.join("run").display().to_string(),
        "/proc/swarm-no-such-dir".to_string(),
    ] {
        let o = std::process::Command::new(orchestrator())
            .args([
                "up",
                "--quiet",
                "--robots",
                "2",
                "--max-ticks",
                "3",
                "--out",
            ])
            .arg(&out)
            .output()
            .unwrap();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "--out {out}: {err}");
        assert!(err.contains("--out") && err.contains(&out), "{err}");
    }
}

/// Runs `orchestrator up ARGS` under an open-files limit of soft / hard.
fn up_with_nofile(soft: u64, hard: u64, args: &[&str]) -> std::process::Output {
    use std::os::unix::process::CommandExt;
    let mut c = std::process::Command::new(orchestrator());
    c.arg("up").arg("--quiet").args(args);
    // SAFETY: setrlimit only, between fork and exec.
    unsafe {
        c.pre_exec(move || {
            let r = libc::rlimit {
                rlim_cur: soft,
                rlim_max: hard,
            };
            if libc::setrlimit(libc::RLIMIT_NOFILE, &r) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    c.output().unwrap()
}

/// Issue 14 item 5: a run that cannot fit under the hard open-files limit is refused at once
/// (exit 2, naming the limit to raise) instead of EMFILE in the world after seconds; a low
/// soft limit under a high hard one is raised, so the run works.
#[test]
fn the_open_files_limit_is_raised_or_the_run_refused() {
    let _g = serial();
    let hard = {
        let mut r = libc::rlimit {
            rlim_cur: 0,
            rlim_max: 0,
        };
        // SAFETY: getrlimit with a valid pointer.
        unsafe { libc::getrlimit(libc::RLIMIT_NOFILE, &mut r) };
        r.rlim_max
    };
    let out = tmp_dir("nofile-refused");
    let o = up_with_nofile(
        1024,
        1024,
        &["--robots", "4096", "--out", out.to_str().unwrap()],
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("RLIMIT_NOFILE") && err.contains("ulimit -Hn"),
        "{err}"
    );
    assert!(!out.exists(), "refused before the run folder is made");
    // 150 robots need ~1,832 descriptors in the world: more than a soft 256, fine once raised.
    if hard >= 4096 {
        let out = tmp_dir("nofile-raised");
        let o = up_with_nofile(
            256,
            hard,
            &[
                "--robots",
                "150",
                "--max-ticks",
                "3",
                "--scenario",
                roam(),
                "--out",
                out.to_str().unwrap(),
            ],
        );
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        assert_left_nothing(&out);
    }
}

/// Issue 37's bad inputs, each refused where it arises: exit 2 naming the file, the key path
/// and its line (or the flag), nothing started.
#[test]
fn the_issue_37_inputs_are_refused_at_their_key_and_line() {
    let _g = serial();
    let dir = tmp_dir("bad-37");
    std::fs::create_dir_all(&dir).unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let config = |name: &str| root.join("configs").join(name).display().to_string();
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p.display().to_string()
    };
    // A kill tick above i64::MAX panicked (exit 101) writing the resolved scenario.
    expect_rejected(
        &["--robots", "3", "--chaos-at", "9223372036854775808:0"],
        &["--chaos-at", "faults.kill_at[0]", "0..=100000000"],
    );
    // /dev/zero was read until the OOM killer.
    expect_rejected(
        &["--scenario", "/dev/zero"],
        &["/dev/zero", "larger than 4 MiB"],
    );
    // 10,000 discs were accepted (and the optimiser spent minutes in one tick).
    let discs: String = (0..10_000)
        .map(|k| format!("[[arena.discs]]\nname = \"d{k}\"\ncentre = [5.0, 5.0]\nradius = 0.1\n"))
        .collect();
    let f = write("discs.toml", &format!("[run]\nrobots = 3\n\n{discs}"));
    expect_rejected(
        &["--scenario", &f],
        &[
            "discs.toml:4:",
            "`arena.discs`",
            "10000 entries",
            "at most 64",
        ],
    );
    // Hunt values: NaN, negative and zero slowdowns, NaN and negative auctioneer ranges.
    let hunt = std::fs::read_to_string(config("hunt-auction.toml")).unwrap();
    let line_of = |text: &str, starts: &str| {
        1 + text
            .lines()
            .position(|l| l.starts_with(starts))
            .expect("the line")
    };
    for (key, was, bad) in [
        (
            "encirclement_slowdown",
            "encirclement_slowdown = 2.0",
            "nan",
        ),
        (
            "encirclement_slowdown",
            "encirclement_slowdown = 2.0",
            "-5.0",
        ),
        (
            "encirclement_slowdown",
            "encirclement_slowdown = 2.0",
            "0.0",
        ),
        ("radio_range", "radio_range = 0.0", "nan"),
        ("radio_range", "radio_range = 0.0", "-1.0"),
    ] {
        let text = hunt.replace(was, &format!("{key} = {bad}"));
        let line = line_of(&text, &format!("{key} = {bad}"));
        let f = write("hunt.toml", &text);
        let section = if key == "radio_range" {
            "hunt.auctioneer"
        } else {
            "hunt.params"
        };
        expect_rejected(
            &["--scenario", &f, "--executor", "inprocess"],
            &[&format!("hunt.toml:{line}:"), &format!("`{section}.{key}`")],
        );
    }
    // A row's value is keyed at its row's line, not at the [hunt] header.
    let text = hunt.replacen("\nspeed = 0.8", "\nspeed = -0.8", 1);
    let line = line_of(&text, "speed = -0.8");
    let f = write("hunt.toml", &text);
    expect_rejected(
        &["--scenario", &f, "--executor", "inprocess"],
        &[&format!("hunt.toml:{line}:"), "`hunt.robots[0].speed`"],
    );
    // A section the run does not use: named, with its line and what the run uses.
    let f = write(
        "roam-formation.toml",
        "[run]\nbehaviour = \"roam\"\n\n[formation]\nepsilon = -1.0\n",
    );
    expect_rejected(
        &["--scenario", &f],
        &[
            "roam-formation.toml:4:",
            "`formation`",
            "\"roam\"",
            "[roam]",
        ],
    );
    expect_rejected(
        &["--scenario", &config("hunt-cbca-example1.toml")],
        &["hunt-cbca-example1.toml:18:", "`cbca`", "\"search\""],
    );
    // An experiment file given to `up`: the error names the line of its `kind` key.
    let kind_line = std::fs::read_to_string(config("cbca-experiment.toml"))
        .unwrap()
        .lines()
        .position(|l| l.starts_with("kind"))
        .expect("the experiment file has a kind")
        + 1;
    let at_kind = format!("cbca-experiment.toml:{kind_line}:");
    expect_rejected(
        &["--scenario", &config("cbca-experiment.toml")],
        &[at_kind.as_str(), "`kind`", "orchestrator experiment"],
    );
    // Integer overflow: key and range.
    let f = write("big.toml", "[run]\nrobots = 99999999999999999999\n");
    expect_rejected(
        &["--scenario", &f],
        &["big.toml:2:", "`run.robots`", "9223372036854775807"],
    );
    let f = write("u32.toml", "[run]\nrobots = 9999999999\n");
    expect_rejected(
        &["--scenario", &f],
        &["u32.toml:2:", "`run.robots`", "0..=4294967295"],
    );
    // Subnormals in exponent form, not 324 digits; a 1 MB string not echoed back.
    let f = write(
        "sub.toml",
        "[arena]\nstart_region = [5e-324, 0.0, 0.0, 1.0]\n",
    );
    expect_rejected(&["--scenario", &f], &["sub.toml:2:", "5e-324"]);
    let f = write(
        "long.toml",
        &format!("[run]\nbehaviour = \"{}\"\n", "x".repeat(1 << 20)),
    );
    expect_rejected(
        &["--scenario", &f],
        &["long.toml:2:", "`run.behaviour`", "1048576 bytes"],
    );
    // A bad built-in letter is `formation.template_name`, not `formation.template`.
    let formation = std::fs::read_to_string(config("formation.toml")).unwrap();
    assert!(formation.contains("template_name = \"C\""));
    let text = formation.replacen("template_name = \"C\"", "template_name = \"Z\"", 1);
    let line = line_of(&text, "template_name = \"Z\"");
    let f = write("letter.toml", &text);
    expect_rejected(
        &["--scenario", &f, "--executor", "inprocess"],
        &[&format!("letter.toml:{line}:"), "`formation.template_name`"],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every error message of the cases above stays short: none echoes its input whole.
#[test]
fn refusals_do_not_echo_huge_inputs() {
    let _g = serial();
    let dir = tmp_dir("bad-37-echo");
    std::fs::create_dir_all(&dir).unwrap();
    for (name, text) in [
        (
            "key.toml",
            format!("[radio]\n{} = 1\n", "k".repeat(1 << 20)),
        ),
        (
            "mode.toml",
            format!("[search]\nmode = \"{}\"\n", "é".repeat(100)),
        ),
        (
            "name.toml",
            format!(
                "[[arena.obstacles]]\nname = \"{}\"\npoints = [[1.0, 1.0]]\n",
                "n".repeat(200)
            ),
        ),
    ] {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        let out = tmp_dir("bad-37-echo-run");
        let o = up(&["--scenario", p.to_str().unwrap()], &out);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(
            err.len() < 1_000,
            "{name}: {} bytes: {}",
            err.len(),
            &err[..300]
        );
        assert!(err.contains(&format!("{name}:")), "{name}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
