//! The agent SDK: everything an agent process does (arguments, scenario, attach, barrier,
//! transport, restart, the seeded random streams, the ack), for any [`Behaviour`]. The built-in
//! `agent` binary is one user of it; a program of the user's (a crate outside this workspace,
//! or the Python package) is another, named by the scenario's `[[agents]]`.
//!
//! ```no_run
//! use swarm::agent::Agent;
//! use swarm::scenario::ConfigError;
//! # struct Boids;
//! # impl swarm::Behaviour for Boids {
//! #     type Msg = ();
//! #     fn step_refs(&mut self, _: &swarm::Sense, _: &[&swarm::Received<()>],
//! #         _: &mut swarm::Outbox<()>) -> swarm::Command { Default::default() }
//! # }
//! # #[derive(serde::Deserialize)] struct Params {}
//! # impl Boids { fn new(_: Params, _: u32) -> Boids { Boids } }
//! fn main() {
//!     swarm::agent::main(|a: &Agent| Ok::<_, ConfigError>(Boids::new(a.params()?, a.robot())))
//! }
//! ```

mod args;
mod params;
mod run_loop;

pub use args::AgentArgs;

use crate::barrier::{BarrierError, TickBarrier};
use crate::scenario::{AgentEntry, ConfigError, Scenario};
use crate::transport::TransportError;
use crate::{AgentRuntime, Behaviour};

/// Exit codes of an agent process.
/// The run ended (the world's shutdown word).
pub const EXIT_OK: i32 = 0;
/// Bad arguments, scenario or parameters (the message names which).
pub const EXIT_BAD_INPUT: i32 = 2;
/// The world is gone (or the run ended while this agent was starting).
pub const EXIT_WORLD_GONE: i32 = 3;
/// The run's services or barrier could not be opened.
pub const EXIT_SETUP: i32 = 4;
/// The behaviour failed (the Python package's agent: `step` raised; the traceback is in the
/// robot's log). The robot ends as a fault, as a crash does.
pub const EXIT_BEHAVIOUR_FAULT: i32 = 5;

/// How an agent process ended, for a fault's cause: its wait status (waitpid) in words.
pub fn exit_cause(status: i32) -> String {
    if libc::WIFEXITED(status) {
        match libc::WEXITSTATUS(status) {
            EXIT_BEHAVIOUR_FAULT => format!(
                "exit code {EXIT_BEHAVIOUR_FAULT}, its behaviour raised an exception (the \
                 traceback is in the robot's log)"
            ),
            c => format!("exit code {c}"),
        }
    } else {
        let sig = libc::WTERMSIG(status);
        format!("signal {sig}")
    }
}

/// The first stream number of the user's own random streams ([`Agent::rng`]): above every
/// stream the runtime uses (`crate::streams`), so user draws never shift the runtime's.
pub const USER_STREAMS: u64 = 1 << 32;

/// Why an agent could not start or stopped before the run ended.
#[derive(Debug, thiserror::Error)]
pub enum AgentError {
    /// The command line is not `--robot I --prefix P --scenario FILE [--run-id R]`.
    #[error("{0}")]
    Args(#[from] clap::Error),
    /// The scenario file could not be read or is invalid.
    #[error(transparent)]
    Scenario(#[from] ConfigError),
    #[error("--robot {robot} is out of range: allowed 0..={}", robots - 1)]
    RobotOutOfRange { robot: u32, robots: u32 },
    /// An iceoryx2 call failed (which service, and iceoryx2's error, are in it).
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// The run's tick barrier segment could not be opened.
    #[error(transparent)]
    Barrier(#[from] BarrierError),
    /// The SIGBUS guard could not be installed.
    #[error(transparent)]
    Guard(#[from] crate::shrink_guard::GuardError),
}

impl AgentError {
    /// The exit code an agent program ends with for this error.
    pub fn exit_code(&self) -> i32 {
        match self {
            AgentError::Args(_) | AgentError::Scenario(_) | AgentError::RobotOutOfRange { .. } => {
                EXIT_BAD_INPUT
            }
            AgentError::Transport(_) | AgentError::Barrier(_) | AgentError::Guard(_) => EXIT_SETUP,
        }
    }
}

/// One robot's agent: what the orchestrator handed it, and the scenario it read.
pub struct Agent {
    args: AgentArgs,
    scenario: Scenario,
    /// This robot's `[[agents]]` entry (its index), if it has one.
    entry: Option<usize>,
}

impl Agent {
    /// Parses the arguments (argv without the program name) and loads the resolved scenario.
    /// Also asks the kernel to kill this process when its parent (the orchestrator) dies,
    /// and quiets iceoryx2's own logging.
    pub fn from_args<I: IntoIterator<Item = String>>(args: I) -> Result<Agent, AgentError> {
        // Die with the orchestrator (it owns cleanup of the run).
        // SAFETY: prctl with constant arguments.
        unsafe {
            libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
        }
        crate::transport::quiet_logs();
        let args = AgentArgs::parse_from_args("agent", args)?;
        let scenario = Scenario::load(&args.scenario)?;
        Agent::new(args, scenario)
    }

    /// An agent for already parsed arguments and a loaded scenario.
    pub fn new(args: AgentArgs, scenario: Scenario) -> Result<Agent, AgentError> {
        if args.robot >= scenario.run.robots {
            return Err(AgentError::RobotOutOfRange {
                robot: args.robot,
                robots: scenario.run.robots,
            });
        }
        let entry = crate::sections::agents::entry_of(&scenario.agents, args.robot);
        Ok(Agent {
            args,
            scenario,
            entry,
        })
    }

    pub fn robot(&self) -> u32 {
        self.args.robot
    }

    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// The run's iceoryx2 prefix.
    pub fn prefix(&self) -> &str {
        &self.args.prefix
    }

    /// The run id ("" when the orchestrator gave none).
    pub fn run_id(&self) -> &str {
        &self.args.run_id
    }

    /// This robot's `[[agents]]` entry, if the scenario lists it.
    pub fn entry(&self) -> Option<&AgentEntry> {
        self.entry.map(|i| &self.scenario.agents[i])
    }

    /// This robot's parameter table (its `[[agents]]` entry's `params`), deserialised into
    /// the program's type; errors name the scenario file, the key path
    /// (`agents[1].params.gain`) and the line. With no entry the table is empty.
    pub fn params<T: serde::de::DeserializeOwned>(&self) -> Result<T, ConfigError> {
        let entry = self.entry.map(|i| (i, &self.scenario.agents[i]));
        params::read(entry, &self.args.scenario.display().to_string())
    }

    /// The seeded random stream `n` of this robot for the program's own draws: the same
    /// numbers in every run of the same seed, and apart from every stream of the runtime.
    pub fn rng(&self, n: u64) -> rand_chacha::ChaCha8Rng {
        crate::streams::rng(
            self.scenario.run.seed,
            self.args.robot,
            USER_STREAMS.wrapping_add(n),
        )
    }

    /// Runs the behaviour until the run ends: attach, barrier, transport, every tick's step
    /// and ack. Returns the process exit code ([`EXIT_OK`], [`EXIT_WORLD_GONE`]). An error
    /// when the run is over already (a restarted agent starting as the run ends) is no fault
    /// of the agent's: it returns [`EXIT_WORLD_GONE`] then.
    pub fn run<B: Behaviour>(self, behaviour: B) -> Result<i32, AgentError> {
        let rt = AgentRuntime::new(&self.scenario, self.args.robot, behaviour);
        match run_loop::run_loop(&self.args.prefix, &self.scenario, self.args.robot, rt) {
            Ok(code) => Ok(code),
            Err(e) => {
                let run_over = TickBarrier::open_agent(&self.args.prefix)
                    .map(|b| b.is_shutdown())
                    .unwrap_or(true);
                if run_over {
                    Ok(EXIT_WORLD_GONE)
                } else {
                    Err(e)
                }
            }
        }
    }
}

/// The Agent of `std::env::args`, or the process exits: --help, --version and argument errors
/// as clap prints them, anything else printed with the agent exit code it maps to.
pub fn from_env_or_exit() -> Agent {
    match Agent::from_args(std::env::args().skip(1)) {
        Ok(a) => a,
        Err(AgentError::Args(e)) => e.exit(),
        Err(e) => {
            eprintln!("agent: {e}");
            std::process::exit(e.exit_code());
        }
    }
}

/// The whole `main` of an agent program: parses `std::env::args`, builds the behaviour with
/// `make` (an error there is printed with the robot id and exits [`EXIT_BAD_INPUT`]), runs
/// it, and exits with the agent exit codes.
pub fn main<B: Behaviour, E: std::fmt::Display>(make: impl FnOnce(&Agent) -> Result<B, E>) -> ! {
    let agent = from_env_or_exit();
    let robot = agent.robot();
    let behaviour = match make(&agent) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("agent {robot}: {e}");
            std::process::exit(EXIT_BAD_INPUT);
        }
    };
    match agent.run(behaviour) {
        Ok(code) => std::process::exit(code),
        Err(e) => {
            eprintln!("agent {robot}: {e}");
            std::process::exit(e.exit_code());
        }
    }
}

/// Runs `Agent::run` on the scenario's behaviour (the visitor of [`main_of`]).
struct RunBehaviour(Agent);

impl crate::plugin::BehaviourVisitor for RunBehaviour {
    type Out = Result<i32, AgentError>;
    fn visit<B: Behaviour + Send + 'static>(self, make: &dyn Fn(u32) -> B) -> Self::Out
    where
        B::Msg: Send + Sync,
    {
        let b = make(self.0.robot());
        self.0.run(b)
    }
}

/// The whole `main` of a composed agent binary (bins/src/bin/agent.rs): registers plug-in
/// `P`'s sections, attaches, runs the scenario's `run.behaviour` (one of `P`'s), exits with
/// the agent exit codes.
pub fn main_of<P: crate::plugin::Plugin>() -> ! {
    crate::plugin::register_plugin::<P>();
    let agent = from_env_or_exit();
    let robot = agent.robot();
    // The dispatch reads the scenario while the visitor owns the agent.
    let sc = agent.scenario().clone();
    match P::dispatch(&sc, RunBehaviour(agent)) {
        Ok(Ok(code)) => std::process::exit(code),
        Ok(Err(e)) => {
            eprintln!("agent {robot}: {e}");
            std::process::exit(e.exit_code());
        }
        Err(_) => {
            eprintln!(
                "agent {robot}: run.behaviour = {:?} is none of this program's: {:?}",
                sc.run.behaviour,
                crate::plugin::behaviour_names::<P>()
            );
            std::process::exit(EXIT_BAD_INPUT);
        }
    }
}
