//! The formation scenario on inputs nobody tuned for (docs/formation.md 9, "Unseen inputs (9
//! robots)"): a typo under `formation.kernels` is refused (it used to be ignored), a template
//! no alpha separates is refused, and obstacles that leave no room for the pattern make the
//! run say NO FEASIBLE PATTERN (it used to fall back to `formation.transform` silently).

use e2e::*;
use std::path::PathBuf;

fn base() -> String {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../configs/formation.toml");
    std::fs::read_to_string(p).unwrap()
}

fn write(dir: &std::path::Path, name: &str, text: &str) -> String {
    std::fs::create_dir_all(dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

/// configs/formation.toml with its two discs replaced by one of `radius` mid-box.
fn with_one_disc(radius: f64) -> String {
    let text = base();
    let (i, j) = (
        text.find("[[arena.discs]]").unwrap(),
        text.find("[robot]").unwrap(),
    );
    format!(
        "{}[[arena.discs]]\nname = \"BIG\"\ncentre = [12.0, 12.0]\nradius = {radius:.1}\n\n{}",
        &text[..i],
        &text[j..]
    )
}

#[test]
fn bad_formation_inputs_are_refused_naming_file_line_key_and_allowed_values() {
    let _g = serial();
    let dir = tmp_dir("formation-inputs");
    let typo = write(
        &dir,
        "typo.toml",
        &format!("{}\n[formation.kernels.optimiser]\nmax_node = 10\n", base()),
    );
    let line = base().lines().count() + 3;
    let out = dir.join("typo-run");
    let o = up(&["--scenario", &typo, "--executor", "inprocess"], &out);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    for m in [
        &format!("typo.toml:{line}") as &str,
        "formation.kernels.optimiser.max_node",
        "allowed keys",
        "max_nodes",
        "alpha_range",
    ] {
        assert!(err.contains(m), "{m:?} in {err}");
    }
    assert!(!out.exists());
    // Nine points on top of each other: no alpha separates them.
    let dup = write(
        &dir,
        "dup.toml",
        &base().replace(
            "template_name = \"C\"\n",
            "template_name = \"dot\"\ntemplate = [[0, 0], [0, 0], [0, 0], [0, 0], [0, 0], [0, 0], [0, 0], [0, 0], [0, 0]]\n",
        ),
    );
    let o = up(
        &["--scenario", &dup, "--executor", "inprocess"],
        &dir.join("dup-run"),
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    for m in [
        "dup.toml:",
        "formation.template",
        "no pattern is feasible",
        "alpha_range",
    ] {
        assert!(err.contains(m), "{m:?} in {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_disc_that_leaves_no_room_for_the_pattern_says_no_feasible_pattern() {
    let _g = serial();
    let dir = tmp_dir("formation-nofit");
    // One disc of radius 10 mid-box: its keep-out square (half-side 10 + r + 0.1) covers the
    // whole [r, 24 - r] box the targets may use; the corners still hold the starts.
    let text = with_one_disc(10.0);
    let sc = write(&dir, "nofit.toml", &text);
    let out = dir.join("run");
    let o = up(
        &[
            "--scenario",
            &sc,
            "--executor",
            "inprocess",
            "--max-ticks",
            "30",
        ],
        &out,
    );
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    assert!(text.contains("NO FEASIBLE PATTERN"), "{text}");
    let f = summary(&out)["mission"]["formation"].clone();
    assert_eq!(f["no_feasible_pattern"], true, "{f}");
    assert_eq!(f["plans"][0]["feasible"], false, "{f}");
    assert_eq!(f["formed"], false);
    assert_eq!(f["overlapping_pairs"], 0);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn robots_squeezed_into_a_corner_by_a_big_disc_slide_along_the_walls_to_their_slots() {
    let _g = serial();
    let dir = tmp_dir("formation-big-disc");
    // One disc of radius 6 mid-box: the optimum puts the C in a corner, slots at r from both
    // walls (C1 allows it). Without the walls' half-planes (walls.rs) ORCA kept steering
    // robots into a wall, the world refused the step, and seeds 2 and 5 never formed.
    let on = write(&dir, "big.toml", &with_one_disc(6.0));
    let off = write(
        &dir,
        "big-off.toml",
        &format!(
            "{}\n[formation.kernels]\nwall_half_planes = false\n",
            with_one_disc(6.0)
        ),
    );
    // The shipped cap is 1000 ticks; both seeds formed by K = 200 on the day, and the stall
    // without the walls' half-planes lasts for good (traced: 3 robots still at tick 1000).
    let run = |sc: &str, seed: &str, name: &str| {
        let out = dir.join(name);
        let o = up(
            &[
                "--scenario",
                sc,
                "--executor",
                "inprocess",
                "--seed",
                seed,
                "--max-ticks",
                "500",
            ],
            &out,
        );
        assert!(ended_by_itself(&o), "{}", stderr(&o));
        summary(&out)["mission"]["formation"].clone()
    };
    for seed in ["2", "5"] {
        let f = run(&on, seed, &format!("on-{seed}"));
        assert_eq!(f["formed"], true, "seed {seed}: {f}");
        assert_eq!(f["overlapping_pairs"], 0, "seed {seed}");
        assert_eq!(f["obstacle_overlaps"], 0, "seed {seed}");
    }
    // The cause, located: the same run without the walls' half-planes stalls in the corner.
    let f = run(&off, "2", "off-2");
    assert_eq!(f["formed"], false, "{f}");
    let _ = std::fs::remove_dir_all(&dir);
}
