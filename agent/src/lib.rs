//! The robot side: the built-in behaviours (one per scenario); the agent process loop is
//! `swarm::agent`.

pub mod behaviours;
pub mod cbca;
pub mod formation;
pub mod hunt;
pub mod kernels;

pub use behaviours::{dispatch, BehaviourVisitor};
