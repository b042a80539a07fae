//! The formation paper's algorithm kernels (Zhang et al., Control and Decision 2024, "Assignment
//! algorithm of multi robot pattern formation based on multi parameter optimization"; spec:
//! docs/formation.md). Pure functions over plain data, no runtime I/O, so a behaviour and a
//! mission can wire them later:
//!
//! - [`params`]: every chosen number, documented (the paper publishes almost none).
//! - [`template`]: patterns as data (the letters C, n, r) and the transform of eq. (5).
//! - [`hungarian`]: the minimum-cost assignment (Kuhn 1955, the paper's ref. \[20\]).
//! - [`constraints`]: the pattern constraints of eqs. (9)-(13).
//! - [`optimise`]: eqs. (1)-(14), solved to the global optimum by spatial branch-and-bound.
//! - [`centroid_repair`]: the nearest feasible centroid for one shape (the search's incumbents).
//! - [`alignment`]: the polygon of achievable alignments, which gives the branch-and-bound its
//!   assignment bound without a Hungarian solve a node.
//! - [`preferred`]: the preferred velocity of eq. (16).
//! - [`orca`] and [`linear_program`]: eqs. (17)-(26), ORCA (van den Berg et al. 2011).
//! - [`walls`]: the box's walls as velocity half-planes (beyond the paper).
//! - [`swaps`]: beyond the paper, a decentralised pairwise-swap reassignment.

pub mod alignment;
pub mod blocked;
pub mod centroid_repair;
pub mod constraints;
pub mod hungarian;
pub mod linear_program;
pub mod optimise;
pub mod orca;
pub mod params;
pub mod preferred;
pub mod swaps;
pub mod template;
pub mod walls;

#[cfg(test)]
mod blocked_tests;
#[cfg(test)]
mod sim_tests;
#[cfg(test)]
mod test_support;

pub use params::{
    FormationParams, ObstacleConstraint, OptimiserBound, OptimiserParams, TransformReading,
};
pub use template::{Template, Transform};

use thiserror::Error;

/// What can go wrong in the formation kernels.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum FormationError {
    /// The template must have one point per robot (the paper's n targets for n robots).
    #[error("the template has {template} points but there are {robots} robots")]
    SizeMismatch { template: usize, robots: usize },
    /// A cost, position or parameter was NaN or infinite.
    #[error("a non-finite number in {0}")]
    NonFinite(&'static str),
    /// No (alpha, d, theta) in the search domain satisfies eqs. (9)-(13).
    #[error("no pattern placement satisfies the box, obstacle and separation constraints")]
    Infeasible,
    /// A range was given with its lower end above its upper end.
    #[error("the range {name} = [{lo}, {hi}] is empty")]
    EmptyRange {
        name: &'static str,
        lo: f64,
        hi: f64,
    },
}
