//! The world: ground truth, sensing, physics, radio accounting, mission metrics, outputs.
//!
//! `World` is a pure state machine (`sense` for every robot, then `apply` the actions); the
//! world process drives it over iceoryx2, the in-process executor drives it directly.

pub mod body;
pub mod data_plane;
pub mod heard;
pub mod kinematics;
pub mod limits;
pub mod medium;
pub mod metrics;
pub mod mission;
pub mod output;
pub mod placement;
pub mod process;
pub mod process_main;
pub mod read_watchdog;
pub mod sensing;
pub mod shrink_guard;
pub mod status_out;
pub mod svg;
pub mod world;

pub use output::{RunOutputs, Summary, Timing};
pub use world::World;
