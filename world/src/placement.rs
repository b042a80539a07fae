//! Initial robot placement: uniform in the start region, outside every obstacle; robots with a
//! body (`robot.radius` > 0) also clear of the walls and of each other.

use crate::body::Statics;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use swarm::geometry::{point_in_polygon, polygon_distance, Vec2};
use swarm::scenario::Scenario;

/// Clearance kept between a start position and any obstacle boundary (point robots; a disc
/// robot keeps at least its radius).
const START_CLEARANCE: f64 = 1.0;
/// Tries per robot before placement gives up.
const TRIES: usize = 10_000;

#[derive(Debug, thiserror::Error)]
pub enum PlacementError {
    #[error("arena.start_region: no free start position for robot {robot} (obstacles, walls or other robots cover it)")]
    NoRoom { robot: u32 },
}

pub fn place_robots(sc: &Scenario, rng: &mut ChaCha8Rng) -> Result<Vec<[f64; 2]>, PlacementError> {
    let [x0, y0, x1, y1] = sc.arena.start_region;
    let r = sc.robot.radius;
    let statics = (r > 0.0).then(|| Statics::new(sc));
    let mut out: Vec<[f64; 2]> = Vec::with_capacity(sc.run.robots as usize);
    for i in 0..sc.run.robots {
        let mut placed = false;
        for _ in 0..TRIES {
            let p = Vec2::new(rng.gen_range(x0..x1), rng.gen_range(y0..y1));
            let blocked = match &statics {
                None => {
                    sc.arena.obstacles.iter().any(|o| {
                        point_in_polygon(p, &o.points)
                            || polygon_distance(p, &o.points) < START_CLEARANCE
                    }) || sc
                        .arena
                        .discs
                        .iter()
                        .any(|d| d.distance([p.x, p.y]) < START_CLEARANCE)
                }
                Some(st) => {
                    st.clearance([p.x, p.y]) < r.max(START_CLEARANCE)
                        || out
                            .iter()
                            .any(|q| ((q[0] - p.x).powi(2) + (q[1] - p.y).powi(2)).sqrt() < 2.0 * r)
                }
            };
            if !blocked {
                out.push([p.x, p.y]);
                placed = true;
                break;
            }
        }
        if !placed {
            return Err(PlacementError::NoRoom { robot: i });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn disc_robots_start_apart_and_clear() {
        let mut sc = Scenario::roam();
        sc.run.robots = 40;
        sc.robot.radius = 3.0;
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let pts = place_robots(&sc, &mut rng).unwrap();
        let st = Statics::new(&sc);
        for (i, p) in pts.iter().enumerate() {
            assert!(st.clearance(*p) >= 3.0);
            for q in &pts[i + 1..] {
                assert!(((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt() >= 6.0);
            }
        }
        // No room: a start square too small for the discs.
        sc.arena.start_region = [10.0, 10.0, 12.0, 12.0];
        assert!(matches!(
            place_robots(&sc, &mut rng),
            Err(PlacementError::NoRoom { robot: 1 })
        ));
    }
}
