//! The `orchestrator` binary: the command line (`up`, `experiment`, `bench`, `view`, ...).

/// mimalloc, not glibc's malloc: the in-process executor's worker threads each allocate a few
/// dozen blocks per robot-step, and with glibc two threads ran each robot ~20 % slower than one
/// thread did alone (chunk times measured inside one run; 2 independent processes did not slow
/// each other). With mimalloc the two threads' chunks take what they take alone.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    orchestrator::main::<swarm_bins::Builtin>()
}
