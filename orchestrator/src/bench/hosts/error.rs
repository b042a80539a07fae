//! What can make the rows across hosts fail, with what they were doing.

use std::path::PathBuf;

/// A failed step of `bench tick`'s rows across hosts.
#[derive(Debug, thiserror::Error)]
pub enum HostsBenchError {
    /// An `ip` or `tc` command could not be started or did not succeed.
    #[error("`{command}` failed: {message}")]
    Command { command: String, message: String },
    /// A network namespace's handle (`/run/netns/NAME`) could not be opened or entered.
    #[error("network namespace {name}: {source}")]
    Netns {
        name: String,
        source: std::io::Error,
    },
    /// The round trip of a link could not be measured.
    #[error("round trip to {addr}: {source}")]
    Rtt {
        addr: String,
        source: std::io::Error,
    },
    /// A process of a run (`up` in the world's namespace, a host's proxy) could not start.
    #[error("start {what}: {source}")]
    Spawn {
        what: String,
        source: std::io::Error,
    },
    /// A process of a run ended badly; `log` is the end of its stderr.
    #[error("{what} {status}; its stderr ends: {log}")]
    Exited {
        what: String,
        status: String,
        log: String,
    },
    /// A run did not end within its time limit (it was stopped).
    #[error("{what} did not end within {seconds} s")]
    Timeout { what: String, seconds: u64 },
    /// The run's scenario file could not be written.
    #[error("{}: {source}", path.display())]
    File {
        path: PathBuf,
        source: std::io::Error,
    },
}
