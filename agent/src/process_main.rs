//! `agent --robot I ...`: one robot's process running a built-in behaviour (the scenario's
//! `run.behaviour`). Started by the orchestrator; the loop is the SDK's (`swarm::agent`).

use crate::behaviours::{dispatch, BehaviourVisitor};
use swarm::agent::{Agent, AgentError};
use swarm::Behaviour;

/// Runs the scenario's behaviour on `Agent`.
struct Run(Agent);

impl BehaviourVisitor for Run {
    type Out = Result<i32, AgentError>;
    fn visit<B: Behaviour + Send + 'static>(self, make: &dyn Fn(u32) -> B) -> Self::Out
    where
        B::Msg: Send + Sync,
    {
        let b = make(self.0.robot());
        self.0.run(b)
    }
}

/// The agent process: attaches to its run, runs the scenario's behaviour, exits.
pub fn main() {
    let agent = swarm::agent::from_env_or_exit();
    let robot = agent.robot();
    // The registry's dispatch reads the scenario while the visitor owns the agent.
    let sc = agent.scenario().clone();
    match dispatch(&sc, Run(agent)) {
        Ok(code) => std::process::exit(code),
        Err(e) => {
            eprintln!("agent {robot}: {e}");
            std::process::exit(e.exit_code());
        }
    }
}
