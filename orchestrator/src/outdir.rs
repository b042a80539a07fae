//! The run folder of `orchestrator up`: made, held by one run at a time, its scenario.toml
//! written whole.

use crate::exit;
use std::os::unix::io::AsRawFd;
use std::path::Path;

/// Why the run folder cannot be used; each names the folder or file and says which exit
/// code it gives.
#[derive(Debug, thiserror::Error)]
pub enum OutDirError {
    #[error("{what}{}: cannot make the run folder: {source}", dir.display())]
    Make {
        what: &'static str,
        dir: std::path::PathBuf,
        source: std::io::Error,
    },
    #[error(
        "{what}{}: another run is writing into this folder right now; give another --out",
        dir.display()
    )]
    Busy {
        what: &'static str,
        dir: std::path::PathBuf,
    },
    #[error("cannot write the run folder: {0}")]
    Write(std::io::Error),
}

impl OutDirError {
    /// A full disk (or quota) fails the run; a folder that cannot be used is bad input.
    pub fn exit_code(&self) -> i32 {
        let full = |e: &std::io::Error| {
            matches!(
                e.kind(),
                std::io::ErrorKind::StorageFull | std::io::ErrorKind::QuotaExceeded
            )
        };
        match self {
            OutDirError::Make { source, .. } if full(source) => exit::FAILED,
            OutDirError::Write(e) if full(e) => exit::FAILED,
            _ => exit::BAD_INPUT,
        }
    }
}

/// The run folder, held for the run: an exclusive lock on the folder itself (released by the
/// kernel when the orchestrator ends, however it ends).
pub struct RunDir {
    _lock: std::fs::File,
}

/// Makes `dir`, locks it against a second run (refused, not waited for) and writes the
/// resolved scenario into it whole. `what` names where the folder came from ("--out ").
pub fn open(dir: &Path, what: &'static str, scenario: &str) -> Result<RunDir, OutDirError> {
    std::fs::create_dir_all(dir).map_err(|source| OutDirError::Make {
        what,
        dir: dir.to_path_buf(),
        source,
    })?;
    let lock = std::fs::File::open(dir).map_err(|source| OutDirError::Make {
        what,
        dir: dir.to_path_buf(),
        source,
    })?;
    // SAFETY: flock on a descriptor this function owns.
    if unsafe { libc::flock(lock.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
        let e = std::io::Error::last_os_error();
        return Err(if e.kind() == std::io::ErrorKind::WouldBlock {
            OutDirError::Busy {
                what,
                dir: dir.to_path_buf(),
            }
        } else {
            OutDirError::Make {
                what,
                dir: dir.to_path_buf(),
                source: e,
            }
        });
    }
    world::output::write_atomic(&dir.join("scenario.toml"), scenario.as_bytes())
        .map_err(OutDirError::Write)?;
    Ok(RunDir { _lock: lock })
}
