//! CBCA, the consensus-based coalition algorithm of thesis 003 chapter 4 (docs/hunting.md
//! sections 4, 5, 8), as pure kernels with their tests: the model (sec. 4.1), the score
//! (4.12)-(4.15), the deadlock-free task graph (4.6)-(4.8), Algorithm 1 (bundle construction),
//! Algorithm 2 (consensus) with a convergence detector, grouping by local prior information
//! (sec. 4.2.2), loyalty and compensation (4.18)-(4.22) and the local-vision re-planning of
//! sec. 4.2.5. No I/O: the runtime carries the messages.

pub mod baselines;
pub mod bundle;
pub mod compare;
pub mod consensus;
pub mod dag;
pub mod grouping;
pub mod idle;
pub mod instance;
pub mod loyalty;
pub mod model;
pub mod moving_rounds;
pub mod narrative;
pub mod narrative_thesis;
pub mod params;
pub mod replan;
pub mod rounds;
pub mod scenario;
pub mod score;
pub mod winners;

pub use model::{Resources, Robot, RobotId, Task, TaskBook, TaskId, RESOURCE_TYPES};
pub use params::{CbcaParams, Consumption, LoyaltyParams};

#[cfg(test)]
mod example1;
#[cfg(test)]
mod example2;
#[cfg(test)]
mod proptests;
