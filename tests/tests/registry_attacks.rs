//! The run registry under attack (issue 37 items 1, 2): another local user who makes the
//! registry folder first (or a link in its place), entries whose fields are not the
//! project's forms, a link at an entry's temporary name. `up`, `clean`, `status` and `kill`
//! refuse or ignore, and touch nothing: no process killed, no file removed or overwritten.
//!
//! Every test points the orchestrator at a registry of its own (`XDG_RUNTIME_DIR`), so that
//! the runs of other programs on this machine never see what it plants. The attacks as
//! another user need root (`runuser -u nobody`); without it they are skipped, saying so.

use e2e::*;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output};

fn is_root() -> bool {
    // SAFETY: geteuid cannot fail.
    unsafe { libc::geteuid() == 0 }
}

fn uid() -> u32 {
    // SAFETY: as above.
    unsafe { libc::geteuid() }
}

/// A base folder for XDG_RUNTIME_DIR with `mode`.
fn base(tag: &str, mode: u32) -> PathBuf {
    let b = tmp_dir(tag);
    std::fs::create_dir_all(&b).unwrap();
    std::fs::set_permissions(&b, std::fs::Permissions::from_mode(mode)).unwrap();
    b
}

/// The registry folder the orchestrator uses under `base`.
fn registry_in(base: &Path) -> PathBuf {
    base.join(format!("swarm-runtime-{}", uid()))
}

/// `orchestrator ARGS` with its registry under `base`.
fn orch(base: &Path, args: &[&str]) -> Output {
    Command::new(orchestrator())
        .args(args)
        .env("XDG_RUNTIME_DIR", base)
        .output()
        .unwrap()
}

/// Runs `args` as user nobody.
fn as_nobody(args: &[&str]) {
    let o = Command::new("runuser")
        .args(["-u", "nobody", "--"])
        .args(args)
        .output()
        .unwrap();
    assert!(o.status.success(), "as nobody {args:?}: {}", stderr(&o));
}

/// A process that must survive: its command line names `prefix` (a check by command line
/// alone took it for the run's). In a process group of its own, ended by [`end_victim`].
fn victim(prefix: &str) -> Child {
    use std::os::unix::process::CommandExt;
    Command::new("sh")
        .args(["-c", &format!("sleep 600; : {prefix}")])
        .process_group(0)
        .spawn()
        .unwrap()
}

fn end_victim(mut v: Child) {
    // SAFETY: SIGKILL of the process group this test made (the shell and its sleep).
    unsafe { libc::kill(-(v.id() as i32), libc::SIGKILL) };
    v.wait().unwrap();
}

/// Start time of `pid` (clock ticks after boot, /proc/PID/stat field 22).
fn start_of(pid: u32) -> u64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap();
    let rest = &stat[stat.rfind(')').unwrap() + 1..];
    rest.split_whitespace().nth(19).unwrap().parse().unwrap()
}

/// A registry entry (the fields the orchestrator writes).
fn entry(run_id: &str, prefix: &str, orch: (u32, u64), world: (u32, u64)) -> String {
    serde_json::json!({
        "run_id": run_id, "prefix": prefix,
        "orchestrator_pid": orch.0, "orchestrator_start": orch.1,
        "world_pid": world.0, "world_start": world.1,
        "agent_pids": [world.0], "agent_starts": [world.1],
        "run_dir": "/nonexistent", "tick": 1, "alive": 1, "dead": 0, "restarted": 0
    })
    .to_string()
}

/// A /dev/shm file of the test's own, under a run-shaped prefix no run uses; kept open, so
/// that `clean` never takes it for an orphan whatever the time it takes.
struct ShmDecoy(PathBuf, #[allow(dead_code)] std::fs::File);

impl ShmDecoy {
    fn new(tag: &str) -> (ShmDecoy, String) {
        let prefix = swarm::transport::prefix_for(&own_run_id(tag));
        let p = Path::new("/dev/shm").join(format!("{prefix}decoy"));
        std::fs::write(&p, b"decoy").unwrap();
        let f = std::fs::File::open(&p).unwrap();
        (ShmDecoy(p, f), prefix)
    }
    fn exists(&self) -> bool {
        self.0.exists()
    }
}

impl Drop for ShmDecoy {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// Every command that needs the registry refuses it (exit 1, naming the folder) and touches
/// nothing: the victim lives, the decoys stay, no run folder is made.
fn all_refuse(base: &Path, why: &str, victim: &mut Child, kept: &[&Path], shm: &ShmDecoy) {
    let out = base.join("run-out");
    let out_s = out.display().to_string();
    let reg = registry_in(base).display().to_string();
    for args in [
        vec![
            "up",
            "--quiet",
            "--scenario",
            roam(),
            "--robots",
            "2",
            "--out",
            &out_s,
        ],
        vec!["clean"],
        vec!["status"],
        vec!["kill", "--run", "e2e-planted", "--robot", "0"],
    ] {
        let o = orch(base, &args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(exit::FAILED), "{args:?}: {err}");
        assert!(
            err.contains(&format!("run registry {reg}")) && err.contains(why),
            "{args:?}: {err}"
        );
    }
    assert!(!out.exists(), "up started a run");
    assert!(
        victim.try_wait().unwrap().is_none(),
        "the victim was killed"
    );
    for p in kept {
        assert!(
            std::fs::symlink_metadata(p).is_ok(),
            "{} was removed",
            p.display()
        );
    }
    assert!(shm.exists(), "a /dev/shm file was removed");
}

/// Another user makes the registry folder first (in a shared /tmp-like folder), writable by
/// all, with an entry naming a process to kill, a run id with `../` and a prefix of files to
/// remove; or a link in its place; or the base folder lets others swap it. Before: the next
/// `up` or `clean` SIGKILLed the process and removed the files.
#[test]
fn a_registry_folder_planted_by_another_user_is_refused_and_nothing_is_touched() {
    if !is_root() {
        eprintln!("SKIPPED: the attack as another user needs root (runuser -u nobody)");
        return;
    }
    let _g = serial();
    let (shm, prefix) = ShmDecoy::new("planted");
    let mut v = victim(&prefix);
    let vs = start_of(v.id());

    // 1. nobody's folder, mode 0777, with an entry.
    let b = base("reg-planted", 0o1777);
    let reg = registry_in(&b);
    as_nobody(&["mkdir", "-m", "0777", reg.to_str().unwrap()]);
    let planted = reg.join("e2e-planted.json");
    let text = entry("e2e-planted", &prefix, (0, 0), (v.id(), vs));
    let escape = entry("../decoy", "", (0, 0), (v.id(), vs));
    as_nobody(&[
        "sh",
        "-c",
        "printf '%s' \"$1\" > \"$2\"; printf '%s' \"$3\" > \"$4\"",
        "sh",
        &text,
        planted.to_str().unwrap(),
        &escape,
        reg.join("escape.json").to_str().unwrap(),
    ]);
    let outside = b.join("decoy.json");
    std::fs::write(&outside, "not the registry's").unwrap();
    all_refuse(
        &b,
        "belongs to uid 65534",
        &mut v,
        &[&planted, &outside, &reg.join("escape.json")],
        &shm,
    );

    // 2. A link in the folder's place (to a folder of nobody's).
    let b = base("reg-link", 0o1777);
    let theirs = b.join("theirs");
    as_nobody(&["mkdir", "-m", "0700", theirs.to_str().unwrap()]);
    as_nobody(&[
        "ln",
        "-s",
        theirs.to_str().unwrap(),
        registry_in(&b).to_str().unwrap(),
    ]);
    all_refuse(&b, "symbolic link", &mut v, &[&registry_in(&b)], &shm);

    // 3. A base folder anyone can write to, without the sticky bit: another user could
    //    rename the registry folder away and put theirs in its place.
    let b = base("reg-open-base", 0o777);
    all_refuse(&b, "can be changed by other users", &mut v, &[], &shm);

    // 4. This user's folder, but open to others.
    let b = base("reg-open", 0o700);
    std::fs::create_dir(registry_in(&b)).unwrap();
    std::fs::set_permissions(registry_in(&b), std::fs::Permissions::from_mode(0o755)).unwrap();
    all_refuse(&b, "other users have access", &mut v, &[], &shm);

    end_victim(v);
}

/// In the user's own private registry, entries whose fields are not the project's forms
/// (an empty prefix, a prefix or run id with `../`, a pid whose process is another program
/// or started at another time) are ignored by `clean` and `kill`: no process killed, no file
/// outside the run's own removed. Before: an empty prefix matched every process and every
/// file of /dev/shm, `../` removed files outside the registry.
#[test]
fn entries_of_other_forms_are_ignored_and_only_verified_processes_are_killed() {
    let _g = serial();
    let (shm, prefix) = ShmDecoy::new("fields");
    let mut v = victim(&prefix);
    let vs = start_of(v.id());
    let b = base("reg-fields", 0o700);
    let reg = registry_in(&b);
    std::fs::create_dir(&reg).unwrap();
    std::fs::set_permissions(&reg, std::fs::Permissions::from_mode(0o700)).unwrap();
    let id = |t: &str| own_run_id(t);
    let outside = b.join("decoy.json");
    std::fs::write(&outside, "not the registry's").unwrap();
    let dead_run = id("dead");
    let dead_prefix = swarm::transport::prefix_for(&dead_run);
    let dead_file = Path::new("/dev/shm").join(format!("{dead_prefix}left"));
    std::fs::write(&dead_file, b"left by a dead run").unwrap();
    let planted = [
        // An empty prefix (matched everything), the victim as the run's world.
        (id("empty"), entry(&id("empty"), "", (0, 0), (v.id(), vs))),
        // A run id that climbs out of the registry.
        (
            "escape".to_string(),
            entry(
                "../decoy",
                &swarm::transport::prefix_for("../decoy"),
                (0, 0),
                (v.id(), vs),
            ),
        ),
        // A prefix that climbs out of /dev/shm.
        (
            id("climb"),
            entry(&id("climb"), "sw../../tmp_", (0, 0), (v.id(), vs)),
        ),
        // A valid dead run whose recorded processes are the victim: another program (and
        // once another start time): its files go, the victim stays.
        (
            dead_run.clone(),
            entry(&dead_run, &dead_prefix, (v.id(), vs), (v.id(), vs + 1)),
        ),
    ];
    for (name, text) in &planted {
        std::fs::write(reg.join(format!("{name}.json")), text).unwrap();
    }
    // kill: the victim posing as a run's orchestrator is no live run.
    let o = orch(&b, &["kill", "--run", &dead_run, "--robot", "0"]);
    assert_eq!(o.status.code(), Some(exit::BAD_INPUT), "{}", stderr(&o));
    assert!(stderr(&o).contains("no such live run"), "{}", stderr(&o));
    let o = orch(&b, &["clean"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for name in [id("empty"), "escape".into(), id("climb")] {
        assert!(
            stderr(&o).contains(&format!(
                "ignored {}",
                reg.join(format!("{name}.json")).display()
            )),
            "{name}: {}",
            stderr(&o)
        );
        assert!(
            reg.join(format!("{name}.json")).exists(),
            "{name} was removed"
        );
    }
    assert!(v.try_wait().unwrap().is_none(), "the victim was killed");
    assert!(outside.exists(), "a file outside the registry was removed");
    assert!(shm.exists(), "a /dev/shm file of no run was removed");
    assert!(!dead_file.exists(), "the dead run's own file stays");
    assert!(!reg.join(format!("{dead_run}.json")).exists());
    end_victim(v);
}

/// A link at an entry's temporary name: the entry is written as a new file, the link removed,
/// its target untouched. Before: the write followed the link and overwrote the target.
#[test]
fn a_link_at_the_temporary_name_is_not_followed() {
    let _g = serial();
    let b = base("reg-tmp-link", 0o700);
    let reg = registry_in(&b);
    std::fs::create_dir(&reg).unwrap();
    std::fs::set_permissions(&reg, std::fs::Permissions::from_mode(0o700)).unwrap();
    let precious = b.join("precious");
    std::fs::write(&precious, "precious").unwrap();
    let run_id = own_run_id("tmp-link");
    let link = reg.join(format!(".{run_id}.json.tmp"));
    std::os::unix::fs::symlink(&precious, &link).unwrap();
    let out = tmp_dir("tmp-link-out");
    let o = Command::new(orchestrator())
        .args([
            "up",
            "--quiet",
            "--scenario",
            roam(),
            "--robots",
            "2",
            "--max-ticks",
            "20",
        ])
        .arg("--out")
        .arg(&out)
        .env("XDG_RUNTIME_DIR", &b)
        .env("SWARM_RUN_ID", &run_id)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(exit::COMPLETE), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&precious).unwrap(), "precious");
    assert!(
        std::fs::symlink_metadata(&link).is_err(),
        "the link is gone"
    );
    assert_left_nothing(&out);
}
