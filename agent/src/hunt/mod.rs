//! Kernels of the hunting thesis (003, Sun Ao 2023, chapters 2-3; docs/hunting.md): the model
//! and its constraints, the artificial potential field, the improved auction and the parallel
//! baseline, hunting points and on-line re-planning. Pure functions and state machines with
//! their unit tests; the hunt behaviour, the auctioneer process and the world mission wire them.
//! The evader's escape (eq. 2.17) is world-side: `world::mission::hunt_escape`.

pub mod apf;
pub mod auction;
#[cfg(test)]
mod closed_loop;
pub mod cost;
#[cfg(test)]
mod example_3a;
pub mod hunting_points;
pub mod instance;
pub mod model;
pub mod parallel_auction;
pub mod params;
pub mod replan;
pub mod ring_by_wall;
pub mod scenario;

pub use params::HuntParams;
