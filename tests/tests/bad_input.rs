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
