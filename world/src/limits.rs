//! What the world core needs of a scenario before it starts, checked with the scenario's
//! [`Check`] (so errors name the key, where it came from and why): the memory its tables take
//! (boundary points, the sensing grid, the coverage grid) stays bounded, and the robots can be
//! placed in the start region.
//!
//! A scenario that passes [`validate`] makes [`crate::World::new`] succeed as far as the core is
//! concerned (the mission checks its own setup).

use crate::metrics::COVERAGE_CELL;
use crate::placement::{place_robots, PlacementError};
use crate::sensing::grid_cell;
use swarm::scenario::{Check, ConfigError, Scenario};

/// Most static boundary points (obstacle outlines and sensed walls sampled every
/// `arena.boundary_spacing`) a scenario may ask for: 2 million points take ~80 MB in the
/// sensing grid, already far more than a robot can sense (MAX_OBSTACLE_POINTS of them at once).
pub const MAX_BOUNDARY_POINTS: u64 = 2_000_000;

/// Most cells of the world's sensing grid ((width / cell + 1) x (height / cell + 1), cell =
/// max(robot.sensing_radius / 4, 2.5)): 4 bytes each, so 64 M cells are 256 MB.
pub const MAX_GRID_CELLS: u64 = 64 << 20;

/// Most cells of the coverage grid (COVERAGE_CELL-unit squares, one byte each): 256 M cells,
/// an arena of 320,000 x 320,000 units.
pub const MAX_COVERAGE_CELLS: u64 = 256 << 20;

/// How many boundary points sampling `poly` every `spacing` units gives (as
/// `swarm::geometry::sample_boundary` samples it: ceil(edge / spacing), at least 1 an edge),
/// saturating instead of overflowing.
pub fn boundary_point_count(poly: &[[f64; 2]], spacing: f64) -> u64 {
    let n = poly.len();
    let mut total: u64 = 0;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        let steps = (len / spacing).ceil().max(1.0);
        // f64 -> u64 saturates (and NaN gives 0, which the finiteness checks rule out before).
        total = total.saturating_add(steps as u64);
    }
    total
}

/// Every static boundary point the scenario asks for (see [`crate::sensing::static_points`]).
pub fn boundary_points(sc: &Scenario) -> u64 {
    let spacing = sc.arena.boundary_spacing;
    let mut total: u64 = sc
        .arena
        .obstacles
        .iter()
        .map(|o| boundary_point_count(&o.points, spacing))
        .fold(0, u64::saturating_add);
    for d in &sc.arena.discs {
        total = total.saturating_add(d.boundary_count(spacing));
    }
    if sc.arena.walls_sensed {
        let (w, h) = (sc.arena.width, sc.arena.height);
        total = total.saturating_add(boundary_point_count(
            &[[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]],
            spacing,
        ));
    }
    total
}

fn cells(width: f64, height: f64, cell: f64) -> u64 {
    let cols = (width / cell).ceil() as u64 + 1;
    let rows = (height / cell).ceil() as u64 + 1;
    cols.saturating_mul(rows)
}

/// Checks the world core's limits (after `Scenario::validate`, which makes every value
/// finite and in range).
pub fn validate(sc: &Scenario, c: &Check) -> Result<(), ConfigError> {
    let points = boundary_points(sc);
    if points > MAX_BOUNDARY_POINTS {
        return Err(c.err(
            "arena.boundary_spacing",
            format!(
                "= {} samples the obstacle outlines{} into {points} boundary points: at most \
                 {MAX_BOUNDARY_POINTS} are allowed (each costs memory in the world's sensing \
                 grid); raise the spacing",
                sc.arena.boundary_spacing,
                if sc.arena.walls_sensed {
                    " and the sensed walls"
                } else {
                    ""
                }
            ),
        ));
    }
    let cell = grid_cell(sc);
    let grid = cells(sc.arena.width, sc.arena.height, cell);
    if grid > MAX_GRID_CELLS {
        return Err(c.err(
            "arena.width",
            format!(
                "= {} by arena.height = {}: the world's sensing grid (cells of {cell} units, a \
                 quarter of robot.sensing_radius = {}) would have {grid} cells, at most \
                 {MAX_GRID_CELLS} are allowed; shrink the arena or raise the sensing radius",
                sc.arena.width, sc.arena.height, sc.robot.sensing_radius
            ),
        ));
    }
    let coverage = cells(sc.arena.width, sc.arena.height, COVERAGE_CELL);
    if coverage > MAX_COVERAGE_CELLS {
        return Err(c.err(
            "arena.width",
            format!(
                "= {} by arena.height = {}: the coverage grid ({COVERAGE_CELL}-unit cells) would \
                 have {coverage} cells, at most {MAX_COVERAGE_CELLS} are allowed",
                sc.arena.width, sc.arena.height
            ),
        ));
    }
    // The placement World::new does, with the same seeded stream: if it finds no room for
    // every robot, say so now (with exit 2) rather than from the world process.
    let mut rng = swarm::streams::rng(
        sc.run.seed,
        swarm::streams::WORLD,
        swarm::streams::PLACEMENT,
    );
    place_robots(sc, &mut rng).map_err(|PlacementError::NoRoom { robot }| {
        c.err(
            "arena.start_region",
            format!(
                "= {:?} has no room for robot {robot} of run.robots = {}: the start region must \
                 leave room outside the obstacles{} for every robot",
                sc.arena.start_region,
                sc.run.robots,
                if sc.robot.radius > 0.0 {
                    format!(
                        ", the walls and each other (robot.radius = {})",
                        sc.robot.radius
                    )
                } else {
                    String::new()
                }
            ),
        )
    })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(_: &str) -> String {
        "t.toml".into()
    }

    fn check(sc: &Scenario) -> Result<(), ConfigError> {
        validate(sc, &Check { key_source: &file })
    }

    #[test]
    fn the_count_is_what_sampling_gives() {
        let sq = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
        // 4 edges of 10 units at spacing 3: ceil(10 / 3) = 4 points each.
        assert_eq!(boundary_point_count(&sq, 3.0), 16);
        assert_eq!(
            boundary_point_count(&sq, 3.0) as usize,
            swarm::geometry::sample_boundary(&sq, 3.0).len()
        );
        let sc = Scenario::default();
        assert_eq!(
            boundary_points(&sc) as usize,
            crate::sensing::static_points(&sc).len()
        );
        // 1e-9 spacing: no allocation, a saturated count.
        assert!(boundary_point_count(&sq, 1e-9) > MAX_BOUNDARY_POINTS);
    }

    #[test]
    fn a_tiny_boundary_spacing_is_refused_with_why() {
        let mut sc = Scenario::default();
        check(&sc).unwrap();
        sc.arena.boundary_spacing = 1e-9;
        let e = check(&sc).unwrap_err();
        assert_eq!(e.key, "arena.boundary_spacing");
        assert!(e.to_string().contains("boundary points"), "{e}");
        assert!(e.to_string().contains("t.toml"), "{e}");
    }

    #[test]
    fn a_huge_arena_is_refused_before_its_grids_are_allocated() {
        let mut sc = Scenario::roam();
        sc.arena.width = 1e7;
        sc.arena.height = 1e7;
        sc.arena.walls_sensed = false;
        let e = check(&sc).unwrap_err();
        assert_eq!(e.key, "arena.width");
        assert!(e.to_string().contains("grid"), "{e}");
    }

    #[test]
    fn a_start_region_inside_an_obstacle_is_refused() {
        let mut sc = Scenario::roam();
        sc.arena.obstacles.push(swarm::scenario::Obstacle {
            name: "block".into(),
            points: vec![
                [100.0, 100.0],
                [200.0, 100.0],
                [200.0, 200.0],
                [100.0, 200.0],
            ],
        });
        sc.arena.start_region = [120.0, 120.0, 180.0, 180.0];
        let e = check(&sc).unwrap_err();
        assert_eq!(e.key, "arena.start_region");
        assert!(e.to_string().contains("no room for robot 0"), "{e}");
        // Half of it free: the robots fit.
        sc.arena.start_region = [120.0, 120.0, 280.0, 180.0];
        check(&sc).unwrap();
    }
}
