//! Initial robot placement: uniform in the start region, outside every obstacle.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use swarm::geometry::{point_in_polygon, polygon_distance, Vec2};
use swarm::scenario::Scenario;

/// Clearance kept between a start position and any obstacle boundary.
const START_CLEARANCE: f64 = 1.0;

pub fn place_robots(sc: &Scenario, rng: &mut ChaCha8Rng) -> Result<Vec<[f64; 2]>, String> {
    let [x0, y0, x1, y1] = sc.arena.start_region;
    let mut out = Vec::with_capacity(sc.run.robots as usize);
    for i in 0..sc.run.robots {
        let mut placed = false;
        for _ in 0..10_000 {
            let p = Vec2::new(rng.gen_range(x0..x1), rng.gen_range(y0..y1));
            let blocked = sc.arena.obstacles.iter().any(|o| {
                point_in_polygon(p, &o.points) || polygon_distance(p, &o.points) < START_CLEARANCE
            });
            if !blocked {
                out.push([p.x, p.y]);
                placed = true;
                break;
            }
        }
        if !placed {
            return Err(format!(
                "arena.start_region: no free start position for robot {i} (obstacles cover it)"
            ));
        }
    }
    Ok(out)
}
