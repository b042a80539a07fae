//! `rust-boids`: one robot of a flock. Started by `orchestrator up` for the robots its
//! scenario's `[[agents]]` entry lists (boids.toml); the SDK (`swarm::agent`) does the rest.

mod boids;

use boids::{Boids, BoidsError};

fn main() {
    swarm::agent::main(|a| -> Result<Boids, BoidsError> { Boids::new(a.params()?, a) })
}
