//! The command line as a user meets it: every subcommand's `--help` fits 80 columns, gives
//! every option a description and `up`'s show their defaults; the completion scripts generate and bash
//! parses its own; the short flags run a real run, whose summary fits 80 columns and ends
//! with how to watch it.

use e2e::*;
use std::process::Command;

fn help_of(sub: &[&str]) -> String {
    let o = Command::new(orchestrator())
        .args(sub)
        .arg("--help")
        .output()
        .unwrap();
    assert!(o.status.success(), "{sub:?}: {}", stderr(&o));
    String::from_utf8(o.stdout).unwrap()
}

/// The names listed under "Commands:" of a help text (`help` itself left out).
fn subcommands(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        // A name is indented 2; a wrapped description's next lines, deeper.
        .filter(|l| !l.starts_with("   "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|n| *n != "help")
        .map(String::from)
        .collect()
}

/// Options of a help text without a description. clap prints a described option either on
/// one line, the description after two spaces (`-V, --version  Print version`), or (when some
/// description is long) as a line of its own with the description on the next lines,
/// indented deeper.
fn undescribed(help: &str) -> Vec<String> {
    let lines: Vec<&str> = help.lines().collect();
    let indent = |l: &str| l.len() - l.trim_start().len();
    lines
        .iter()
        .enumerate()
        // An option's or argument's own line: indented 2 to 6 columns (descriptions on lines
        // of their own are indented 10).
        .filter(|(_, l)| (2..=6).contains(&indent(l)) && l.trim_start().starts_with(['-', '<']))
        .filter(|(i, l)| match l.trim().split_once("  ") {
            // Only clap's own brackets (`[possible values: csv, mcap]`) are no description.
            Some((_, text)) => text.trim().starts_with('['),
            None => lines.get(i + 1).is_none_or(|n| {
                n.trim().is_empty() || n.trim().starts_with('[') || indent(n) <= indent(l)
            }),
        })
        .map(|(_, l)| l.trim().to_string())
        .collect()
}

#[test]
fn every_subcommands_help_describes_every_option_and_up_shows_defaults() {
    let mut todo: Vec<Vec<String>> = vec![vec![]];
    let mut walked = 0;
    while let Some(path) = todo.pop() {
        let args: Vec<&str> = path.iter().map(String::as_str).collect();
        let help = help_of(&args);
        for l in help.lines() {
            assert!(l.chars().count() <= 80, "{path:?} --help: {l:?}");
        }
        let bad = undescribed(&help);
        assert!(
            bad.is_empty(),
            "orchestrator {path:?} --help: {bad:?}\n{help}"
        );
        for s in subcommands(&help) {
            let mut p = path.clone();
            p.push(s);
            todo.push(p);
        }
        walked += 1;
    }
    assert!(walked >= 12, "{walked} helps walked");
    // Wrapped lines joined: a bracket may be cut across two.
    let up = help_of(&["up"])
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    let sc = swarm::scenario::Scenario::default();
    for want in [
        format!("[scenario: run.robots, default {}]", sc.run.robots),
        format!("[scenario: run.max_ticks, default {}]", sc.run.max_ticks),
        "[default: processes]".to_string(),
        "-n, --robots".to_string(),
        "-s, --scenario".to_string(),
        "-o, --out".to_string(),
        "-q, --quiet".to_string(),
    ] {
        assert!(up.contains(&want), "up --help lacks {want:?}:\n{up}");
    }
}

#[test]
fn the_completion_scripts_generate_and_bash_parses_its_own() {
    for shell in ["bash", "zsh", "fish"] {
        let o = Command::new(orchestrator())
            .args(["completions", shell])
            .output()
            .unwrap();
        assert!(o.status.success(), "{shell}: {}", stderr(&o));
        let script = String::from_utf8(o.stdout).unwrap();
        // fish names options without their dashes (`-l format`).
        for word in ["export", "format", "mcap", "robots", "scenario"] {
            assert!(script.contains(word), "{shell} completion lacks {word}");
        }
        if shell == "bash" {
            let dir = tmp_dir("completions");
            std::fs::create_dir_all(&dir).unwrap();
            let f = dir.join("orchestrator.bash");
            std::fs::write(&f, &script).unwrap();
            let o = Command::new("bash").arg("-n").arg(&f).output().unwrap();
            assert!(o.status.success(), "bash -n: {}", stderr(&o));
            let _ = std::fs::remove_dir_all(&dir);
        }
    }
}

#[test]
fn short_flags_run_and_the_summary_fits_80_columns_and_says_how_to_watch() {
    let _g = serial();
    let out = tmp_dir("cli-short-flags");
    let o = Command::new(orchestrator())
        .args([
            "up",
            "-q",
            "-n",
            "3",
            "-s",
            roam(),
            "--max-ticks",
            "12",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out);
    assert_eq!(s["robots"], 3);
    assert_eq!(s["ticks"], 12);
    let text = String::from_utf8(o.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    // The last line is the command that shows the run, whole however long; the others fit.
    let (watch, rest) = lines.split_last().expect("a summary");
    for l in rest {
        assert!(l.chars().count() <= 80, "wider than 80 columns: {l:?}");
    }
    assert_eq!(
        watch.trim(),
        format!("{} view {}", orchestrator().display(), out.display()),
        "{text}"
    );
    assert_eq!(
        rest.last().map(|l| l.trim()),
        Some("watch it in the browser:")
    );
    assert_left_nothing(&out);
    let _ = std::fs::remove_dir_all(&out);
}

/// tmux, the terminal of the Ctrl-C test (scripts/test.sh installs Debian's package).
fn tmux(args: &[&str]) -> std::process::Output {
    Command::new("tmux")
        .args(args)
        .output()
        .expect("tmux (Debian package tmux; scripts/test.sh installs it)")
}

/// Polls tmux pane `target` until its text holds `needle`; returns the text.
fn screen_until(target: &str, needle: &str, budget: std::time::Duration) -> String {
    let start = std::time::Instant::now();
    loop {
        let o = tmux(&["capture-pane", "-p", "-t", target]);
        let text = String::from_utf8_lossy(&o.stdout).to_string();
        if text.contains(needle) || start.elapsed() > budget {
            return text;
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
}

#[test]
fn ctrl_c_in_a_real_terminal_leaves_no_progress_bar_on_the_screen() {
    let _g = serial();
    let session = format!("swarm-e2e-{}-ctrl-c", std::process::id());
    let out = tmp_dir("cli-ctrl-c");
    // An 80-column terminal with a shell, as a user has; the run is typed into it.
    let o = tmux(&[
        "new-session",
        "-d",
        "-s",
        &session,
        "-x",
        "80",
        "-y",
        "30",
        "bash",
        "--norc",
    ]);
    assert!(o.status.success(), "tmux: {}", stderr(&o));
    let line = format!(
        "{} up -n 4 -s {} --max-ticks 100000 --tick-hz 40 -o {}",
        orchestrator().display(),
        roam(),
        out.display()
    );
    tmux(&["send-keys", "-t", &session, &line, "Enter"]);
    let budget = std::time::Duration::from_secs(30);
    let running = screen_until(&session, "ticks/s |", budget);
    tmux(&["send-keys", "-t", &session, "C-c"]);
    let after = screen_until(&session, "watch it in the browser", budget);
    tmux(&["kill-session", "-t", &session]);
    assert!(
        running.contains("tick ["),
        "no progress bar drawn:\n{running}"
    );
    assert!(after.contains("interrupted"), "{after}");
    assert!(
        !after.contains("tick [") && !after.contains("ticks/s |"),
        "the progress bar stayed on the screen:\n{after}"
    );
    assert_left_nothing(&out);
    let _ = std::fs::remove_dir_all(&out);
}
