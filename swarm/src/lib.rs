//! Shared library of the swarm runtime.
//!
//! Everything both executors (multi-process and in-process) share lives here, so that the two
//! give byte-identical recordings: the frames, the scenario types and their validation, the
//! radio model (range, loss; the medium`s wire format in `air`), the behaviour API with its agent-side
//! runtime, the in-process radio (`mailbox`), the recording format, and the iceoryx2 / futex
//! plumbing of the multi-process path.

// Linux only: the runtime's futex barrier, /proc reads and shared memory in /dev/shm have no
// equivalent here on other systems; say so at once rather than with errors deep in the build.
#[cfg(not(target_os = "linux"))]
compile_error!(
    "the swarm runtime is Linux-only (futex, /proc, /dev/shm); build it on Linux (README.md)"
);

pub mod agent;
pub mod air;
pub mod barrier;
pub mod behaviour;
pub mod bell;
pub mod blob;
pub mod chaos;
pub mod cleanup;
pub mod frames;
pub mod geometry;
pub mod key_lines;
pub mod layer;
pub mod limits;
pub mod mailbox;
pub mod plugin;
pub mod radio;
pub mod recording;
pub mod scenario;
pub mod scenario_shape;
pub mod sealed;
pub mod sections;
pub mod sense_pack;
pub mod shrink_guard;
pub mod streams;
pub mod toml_u64;
pub mod transport;
pub mod wire;

pub use behaviour::{AgentRuntime, Behaviour, Command, Outbox, Received};
pub use blob::Blob;
pub use frames::{Action, RadioHeader, Sense};
pub use scenario::Scenario;
