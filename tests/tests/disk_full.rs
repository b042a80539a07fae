//! A full disk (issue 37 item 12), on a small tmpfs this test mounts (root only; skipped,
//! saying so, otherwise): at start, mid-run (recording.bin), and at the last output
//! (run.svg). The run fails (exit 1) naming the file, and leaves no empty or cut-short
//! scenario.toml / summary.json / run.svg and no temporary file; /dev/shm clean.

use e2e::*;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A tmpfs of `size_kb` KiB mounted on a fresh folder; unmounted and removed on drop.
struct SmallDisk(PathBuf);

impl SmallDisk {
    fn mount(tag: &str, size_kb: u64) -> Option<SmallDisk> {
        // SAFETY: geteuid cannot fail.
        if unsafe { libc::geteuid() } != 0 {
            eprintln!("SKIPPED: mounting a small tmpfs needs root");
            return None;
        }
        let dir = tmp_dir(tag);
        std::fs::create_dir_all(&dir).unwrap();
        let o = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size_kb}k"), "tmpfs"])
            .arg(&dir)
            .output()
            .unwrap();
        if !o.status.success() {
            eprintln!(
                "SKIPPED: cannot mount a tmpfs here: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            let _ = std::fs::remove_dir(&dir);
            return None;
        }
        Some(SmallDisk(dir))
    }

    /// Bytes free.
    fn free(&self) -> u64 {
        let c = std::ffi::CString::new(self.0.to_str().unwrap()).unwrap();
        // SAFETY: a zeroed statvfs filled by the call.
        let mut st: libc::statvfs = unsafe { std::mem::zeroed() };
        // SAFETY: valid path and out pointer.
        assert_eq!(unsafe { libc::statvfs(c.as_ptr(), &mut st) }, 0);
        st.f_bavail as u64 * st.f_frsize as u64
    }

    /// Fills the disk with a file until `leave` bytes are free (whole pages).
    fn fill_leaving(&self, leave: u64) {
        let size = self.free().saturating_sub(leave);
        std::fs::write(self.0.join("filler"), vec![0u8; size as usize]).unwrap();
    }
}

impl Drop for SmallDisk {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
        let _ = std::fs::remove_dir(&self.0);
    }
}

/// Files of a run folder.
fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

const ROAM_ARGS: [&str; 6] = ["--robots", "6", "--seed", "4", "--max-ticks", "4000"];

fn args(exec: &str) -> Vec<&str> {
    [
        &["--scenario", roam(), "--executor", exec][..],
        &ROAM_ARGS[..],
    ]
    .concat()
}

#[test]
fn a_full_disk_at_start_fails_naming_scenario_toml_and_leaves_no_empty_file() {
    let _g = serial();
    let Some(disk) = SmallDisk::mount("disk-full-start", 64) else {
        return;
    };
    disk.fill_leaving(0);
    let out = disk.0.join("run");
    let o = up(&args("inprocess"), &out);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(exit::FAILED), "{err}");
    assert!(
        err.contains(&format!(
            "{}: No space left on device",
            out.join("scenario.toml").display()
        )),
        "{err}"
    );
    assert_eq!(
        files(&out),
        Vec::<String>::new(),
        "no scenario.toml, no temporary file"
    );
}

#[test]
fn a_disk_that_fills_mid_run_fails_naming_recording_bin_in_both_executors() {
    let _g = serial();
    for exec in ["processes", "inprocess"] {
        // Room for the scenario and a few hundred ticks of the recording, not for 4,000.
        let Some(disk) = SmallDisk::mount(&format!("disk-full-mid-{exec}"), 96) else {
            return;
        };
        let out = disk.0.join("run");
        let id = own_run_id(&format!("disk-full-mid-{exec}"));
        let o = up_as(&args(exec), &out, Some(&id));
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(exit::FAILED), "{exec}: {err}");
        assert!(
            err.contains(&format!(
                "{}: No space left on device",
                out.join("recording.bin").display()
            )),
            "{exec}: {err}"
        );
        // The processes executor's agents write their logs (logs/robot-<i>.log) from the start.
        let mut want = vec!["recording.bin".to_string(), "scenario.toml".to_string()];
        if exec == "processes" {
            want.insert(0, "logs".to_string());
        }
        assert_eq!(
            files(&out),
            want,
            "{exec}: no summary.json, no run.svg, no temporary file"
        );
        assert!(shm_of_run(&id).is_empty(), "{exec}: {:?}", shm_of_run(&id));
        assert!(processes_mentioning(&swarm::transport::prefix_for(&id)).is_empty());
    }
}

/// Room for everything but the picture: run.svg (written last) fails, named, and is absent
/// rather than cut short (before: a truncated run.svg and a raw `Io { .. code: 28 }`).
#[test]
fn a_disk_that_fills_at_the_picture_leaves_no_cut_short_run_svg() {
    let _g = serial();
    // The same run on a roomy disk: the size of each output (the run is deterministic; the
    // summary's timings vary by a few bytes, within its last page).
    let roomy = tmp_dir("disk-full-svg-roomy");
    let few = [
        "--scenario",
        roam(),
        "--executor",
        "inprocess",
        "--robots",
        "6",
        "--max-ticks",
        "1000",
    ];
    let o = up(&few, &roomy);
    assert_eq!(o.status.code(), Some(exit::COMPLETE), "{}", stderr(&o));
    let page = 4096u64;
    let pages = |f: &str| {
        std::fs::metadata(roomy.join(f))
            .unwrap()
            .len()
            .div_ceil(page)
    };
    let (scenario, recording, summary, svg) = (
        pages("scenario.toml"),
        pages("recording.bin"),
        pages("summary.json"),
        pages("run.svg"),
    );
    assert!(
        svg > scenario + 2,
        "the picture is the largest small file: {svg} pages"
    );
    let Some(disk) = SmallDisk::mount("disk-full-svg", 1024) else {
        return;
    };
    // Enough for every file but run.svg (each written under a temporary name first: the
    // scenario's rewrite needs its pages twice for a moment, which the picture's room holds).
    disk.fill_leaving((scenario + recording + summary + svg - 2) * page);
    let out = disk.0.join("run");
    let o = up(&few, &out);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(exit::FAILED), "{err}");
    assert!(
        err.contains(&format!(
            "{}: No space left on device",
            out.join("run.svg").display()
        )),
        "{err}"
    );
    assert!(!out.join("run.svg").exists(), "a cut-short run.svg");
    assert!(
        !out.join(".run.svg.tmp").exists(),
        "the temporary file stays"
    );
    let _ = std::fs::remove_dir_all(&roomy);
}
