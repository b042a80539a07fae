//! The box's walls as velocity constraints (not in the paper: its box appears only in the
//! pattern's constraint C1, eq. 9, and its ORCA, eqs. 17-26, knows robots and obstacles).
//!
//! The world refuses a whole step that would take a disc through a wall (the robot stays
//! put), and ORCA, not knowing the wall, may keep choosing that step: a robot sliding along a
//! wall to a slot that C1 allows at exactly r from it was stuck for good (docs/formation.md 9,
//! "Unseen inputs", disc-big). With these half-planes the step keeps the disc inside the box, so
//! the linear program picks the nearest velocity that slides along the wall instead.
//!
//! For the wall with outward normal u at gap g = (distance from the centre to the wall) - r:
//! u . v tau <= g - cell_slack (the whole gap: a wall does not move), u . v <= 0 once the gap
//! is under the slack, and a negative gap (outside, which the world prevents) asks to come back
//! in. Walls farther than 1.5 steps at V_p add nothing. v = 0 satisfies every one, so with the
//! acceleration polygon holding v = 0 (a tau >= V_p) they never empty the hard set.

use super::linear_program::HalfPlane;
use super::params::FormationParams;
use swarm::geometry::Vec2;

/// The half-planes that keep a disc of the true radius `params.robot_radius` at `position`
/// inside [box_min, box_max] through the next step (none when `params.wall_half_planes` is off).
pub fn wall_half_planes(position: Vec2, params: &FormationParams) -> Vec<HalfPlane> {
    if !params.wall_half_planes {
        return Vec::new();
    }
    let tau = params.time_step;
    let reach = params.max_speed * tau;
    let r = params.robot_radius;
    let walls = [
        (Vec2::new(-1.0, 0.0), position.x - params.box_min[0]),
        (Vec2::new(1.0, 0.0), params.box_max[0] - position.x),
        (Vec2::new(0.0, -1.0), position.y - params.box_min[1]),
        (Vec2::new(0.0, 1.0), params.box_max[1] - position.y),
    ];
    walls
        .iter()
        .filter_map(|&(u, distance)| {
            let gap = distance - r;
            if gap > 1.5 * reach {
                return None;
            }
            let bound = if gap >= 0.0 {
                (gap - params.cell_slack).max(0.0) / tau
            } else {
                gap / tau
            };
            Some(HalfPlane {
                point: u * bound,
                normal: -u,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formation::linear_program::select_velocity;

    #[test]
    fn a_robot_touching_the_floor_may_slide_along_it_but_not_into_it() {
        let p = FormationParams::default();
        // Centre at y = r: the disc touches the wall y = 0.
        let me = Vec2::new(10.0, p.robot_radius);
        let h = wall_half_planes(me, &p);
        assert_eq!(h.len(), 1, "only the floor is near");
        // The preferred velocity points right and down, into the floor.
        let sel = select_velocity(&[], &h, &[], p.max_speed, Vec2::new(0.8, -0.5));
        assert!(
            sel.velocity.y.abs() < 1e-9,
            "no step into the wall: {:?}",
            sel.velocity
        );
        assert!(
            (sel.velocity.x - 0.8).abs() < 1e-9,
            "slides: {:?}",
            sel.velocity
        );
    }

    #[test]
    fn near_a_corner_the_step_stays_in_the_box_and_far_walls_add_nothing() {
        let p = FormationParams::default();
        let tau = p.time_step;
        let me = Vec2::new(
            p.box_max[0] - p.robot_radius - 0.1,
            p.box_min[1] + p.robot_radius + 0.05,
        );
        let h = wall_half_planes(me, &p);
        assert_eq!(h.len(), 2);
        let sel = select_velocity(&[], &h, &[], p.max_speed, Vec2::new(0.7, -0.7));
        let next = me + sel.velocity * tau;
        assert!(next.x <= p.box_max[0] - p.robot_radius + 1e-9, "{next:?}");
        assert!(next.y >= p.box_min[1] + p.robot_radius - 1e-9, "{next:?}");
        let centre = Vec2::new(12.0, 12.0);
        assert!(wall_half_planes(centre, &p).is_empty());
        let off = FormationParams {
            wall_half_planes: false,
            ..p
        };
        assert!(wall_half_planes(me, &off).is_empty());
    }
}
