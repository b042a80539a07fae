//! The arguments the orchestrator gives every agent program (built-in or the user's):
//! `--robot I --prefix P --scenario FILE [--run-id R]`.

use clap::Parser;
use std::path::PathBuf;

#[derive(Parser, Debug, Clone)]
#[command(about = "One robot of a swarm run (started by `orchestrator up`)")]
pub struct AgentArgs {
    /// The robot this process runs.
    #[arg(long)]
    pub robot: u32,
    /// The run's iceoryx2 prefix.
    #[arg(long)]
    pub prefix: String,
    /// The resolved scenario of the run (the run folder's scenario.toml).
    #[arg(long)]
    pub scenario: PathBuf,
    /// The run id (for `ps` and logs).
    #[arg(long, default_value = "")]
    pub run_id: String,
}

impl AgentArgs {
    /// Parses `args` (argv without the program name; `name` stands in for it in messages).
    pub fn parse_from_args<I: IntoIterator<Item = String>>(
        name: &str,
        args: I,
    ) -> Result<AgentArgs, clap::Error> {
        AgentArgs::try_parse_from(std::iter::once(name.to_string()).chain(args))
    }
}
