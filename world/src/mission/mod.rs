//! Mission kernels (world side).

pub mod hunt_escape;
