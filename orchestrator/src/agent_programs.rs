//! Before anything starts: each `[[agents]]` program exists and may be run (a missing one is
//! bad input naming `agents[i].command`, not a failed run).

use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use swarm::scenario::{Check, ConfigError, Scenario};

/// Whether `p` is a file this user may execute (any x bit: the kernel has the last word).
fn executable(p: &Path) -> bool {
    std::fs::metadata(p).is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
}

/// Where `program` is found: itself when it names a path (it holds a `/`; relative ones were
/// made absolute against the scenario's folder), else the first match on PATH.
fn find(program: &str) -> Option<PathBuf> {
    if program.contains('/') {
        let p = PathBuf::from(program);
        return executable(&p).then_some(p);
    }
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|d| d.join(program))
            .find(|p| executable(p))
    })
}

/// Checks that every entry's program and working directory exist.
pub fn check_found(sc: &Scenario, key_source: &dyn Fn(&str) -> String) -> Result<(), ConfigError> {
    let c = Check { key_source };
    for (i, e) in sc.agents.iter().enumerate() {
        let program = &e.command[0];
        if find(program).is_none() {
            let how = if program.contains('/') {
                "no executable file there (relative paths are of the scenario file's folder; \
                 build the program first)"
            } else {
                "no executable of that name on PATH"
            };
            return Err(c.err(
                &format!("agents[{i}].command"),
                format!("runs {program:?}: {how}"),
            ));
        }
        if let Some(cwd) = &e.cwd {
            if !Path::new(cwd).is_dir() {
                return Err(c.err(
                    &format!("agents[{i}].cwd"),
                    format!("= {cwd:?} is not a folder"),
                ));
            }
        }
    }
    Ok(())
}
