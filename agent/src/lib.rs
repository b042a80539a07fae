//! The robot side: behaviours (one per scenario) and the agent process loop.

pub mod behaviours;
pub mod cbca;
pub mod formation;
pub mod hunt;
pub mod kernels;
pub mod process;
pub mod search;

pub use behaviours::{dispatch, BehaviourVisitor};
