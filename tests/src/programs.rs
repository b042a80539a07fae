//! Agent programs of the user's (issue 38) for the e2e tests: the example crates built from
//! the repository, and scenario files whose `[[agents]]` entries name them. A test of another
//! language adds its program beside [`rust_boids`] and passes its entries to
//! [`scenario_with_agents`].

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The repository's root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// examples/rust-boids built (release, into the repository's target folder, as its
/// .cargo/config.toml says; up to date after the first call), its binary's path.
pub fn rust_boids() -> PathBuf {
    static BUILT: OnceLock<PathBuf> = OnceLock::new();
    BUILT
        .get_or_init(|| {
            let dir = repo().join("examples/rust-boids");
            let st = std::process::Command::new(env!("CARGO"))
                .args(["build", "--release", "--quiet"])
                .current_dir(&dir)
                .status()
                .expect("run cargo");
            assert!(st.success(), "building examples/rust-boids failed");
            let bin = crate::bin_dir().join("rust-boids");
            assert!(bin.exists(), "{} missing after the build", bin.display());
            bin
        })
        .clone()
}

/// The weights of examples/rust-boids/boids.toml, as an `[agents.params]` table body.
pub const BOIDS_PARAMS: &str = "cohesion = 0.01\nalignment = 0.125\nseparation = 20.0\n\
                                separation_radius = 25.0\navoid = 40.0\ncruise = 0.6\n";

/// One `[[agents]]` entry of a test scenario.
pub struct Entry<'a> {
    /// The `robots` value as TOML: `"10..20"` (with its quotes) or `[1, 4]`.
    pub robots: &'a str,
    pub command: Vec<String>,
    /// The body of its `[agents.params]` table ("" for none).
    pub params: &'a str,
    /// More keys of the entry, as TOML lines (`attach_timeout_s = 1`).
    pub extra: &'a str,
}

/// The entry running the rust-boids example on `robots`.
pub fn boids_entry(robots: &str) -> Entry<'_> {
    Entry {
        robots,
        command: vec![rust_boids().display().to_string()],
        params: BOIDS_PARAMS,
        extra: "",
    }
}

/// Writes `dir/scenario.toml`: configs/roam.toml (the built-in robots roam) with `head`
/// (more keys of `[run]`, e.g. `robots = 20`) and the `[[agents]]` entries; returns its path.
pub fn scenario_with_agents(dir: &Path, head: &str, entries: &[Entry]) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let roam = std::fs::read_to_string(crate::roam()).unwrap();
    let mut text = roam.replacen("[run]\n", &format!("[run]\n{head}\n"), 1);
    for e in entries {
        let cmd: Vec<String> = e.command.iter().map(|c| format!("{c:?}")).collect();
        text += &format!(
            "\n[[agents]]\nrobots = {}\ncommand = [{}]\n{}",
            e.robots,
            cmd.join(", "),
            e.extra
        );
        if !e.extra.is_empty() && !e.extra.ends_with('\n') {
            text.push('\n');
        }
        if !e.params.is_empty() {
            text += &format!("[agents.params]\n{}", e.params);
        }
    }
    let path = dir.join("scenario.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// 1-based line of the first line of `file` that starts with `prefix`.
pub fn line_starting(file: &Path, prefix: &str) -> usize {
    let text = std::fs::read_to_string(file).unwrap();
    text.lines()
        .position(|l| l.starts_with(prefix))
        .map(|i| i + 1)
        .unwrap_or_else(|| panic!("no line {prefix:?} in {}", file.display()))
}
