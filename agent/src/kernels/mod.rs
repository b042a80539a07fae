//! Kernels every behaviour may use (pure functions with their unit tests): the virtual force
//! of eq. (5), the two nearest of a set of points, obstacle points ahead in a corridor, and
//! the boundary scan of sensed obstacle points. Plane geometry (`Vec2` and its helpers) is
//! `swarm::geometry`, shared with the world. Kernels of one paper stay with it
//! (`crate::search` for the search paper).

pub mod boundary;
pub mod nearest;
pub mod obstacles;
pub mod virtual_force;
