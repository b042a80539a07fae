//! Scenario sections that belong to one paper: what a mission's world side and its behaviours
//! both read. One file per section; the section's validation lives with its owners (the
//! behaviour in the agent crate, the mission in the world crate).

pub mod agents;
pub mod formation;
pub mod hosts;
pub mod hunt;
pub mod hunt_checks;
pub mod roam;
pub mod search;
