//! The hunting problem's entities (thesis sec. 2.1.3, spec 1.1) and its constraints (2.5)-(2.7)
//! plus the speed-capability rule, as pure functions.
//!
//! A robot R_i = <X_i, E_i', l_i> (2.1) carries 6 resource types (2.4) and has a speed and a
//! turn-rate limit (the unicycle of eqs. 2.8-2.10); in chapter 3 it holds one task at a time.
//! A target T_j = <X_j, E_j, L_j, V_a> (2.2) has a required resource vector E_j (2.3), a required
//! number of robots L_j, a reward cap z_jmax (chapter 3) and a speed v_j.

use swarm::geometry::Vec2;

/// Number of resource types z (every experiment of the thesis uses 6, eq. 2.4).
pub const N_RESOURCES: usize = 6;

/// A resource vector: units of each of the z = 6 types (2.3)-(2.4). Counts in the thesis; kept
/// as f64 because (3.9)'s E_ij is a share of them.
pub type Resources = [f64; N_RESOURCES];

/// Robot identifier R_i (1-based as in the thesis's tables).
pub type RobotId = u32;
/// Task (target, evader) identifier T_j (1-based as in the thesis's tables).
pub type TaskId = u32;

/// A heterogeneous hunting robot.
#[derive(Clone, Debug, PartialEq)]
pub struct Robot {
    pub id: RobotId,
    /// X_i, km.
    pub position: Vec2,
    /// phi_i, rad (2.10).
    pub heading: f64,
    /// E_i' (2.4).
    pub resources: Resources,
    /// Matching coefficients g_ij (3.8), indexed by task id - 1 (Table 3.2 lists T1..T5).
    pub matching: Vec<f64>,
    /// v_i, maximum linear speed, km/min.
    pub speed: f64,
    /// w_max, maximum turn rate, rad/min.
    pub turn_rate: f64,
    /// d^c_max,i, the maximum mileage (2.5), km; infinite when the scenario gives none (the
    /// thesis never does).
    pub max_mileage: f64,
    /// d^c_i, the distance travelled so far (2.5), km.
    pub travelled: f64,
}

impl Robot {
    /// g_ij: the robot's matching coefficient for task `task` (0 when the table has none).
    pub fn matching(&self, task: TaskId) -> f64 {
        (task as usize)
            .checked_sub(1)
            .and_then(|k| self.matching.get(k))
            .copied()
            .unwrap_or(0.0)
    }
}

/// A target (evader) and the hunting task it defines.
#[derive(Clone, Debug, PartialEq)]
pub struct Task {
    pub id: TaskId,
    /// X_j, km.
    pub position: Vec2,
    /// E_j (2.3).
    pub resources: Resources,
    /// L_j, the number of robots required.
    pub required_robots: usize,
    /// z_jmax, the reward cap (3.4).
    pub reward_cap: f64,
    /// v_j, km/min.
    pub speed: f64,
    /// The speed-capability requirement (sec. 3.3: R10 "does not meet T3's speed-capability
    /// requirement"): robots slower than this cannot take the task, km/min. 0 = none.
    pub min_robot_speed: f64,
}

/// (2.5) mileage: the robot can still travel `extra` km without exceeding d^c_max,i.
pub fn mileage_ok(robot: &Robot, extra: f64) -> bool {
    robot.travelled + extra <= robot.max_mileage
}

/// (2.6) coalition resources: for every type p, sum over the coalition of E_i'^p >= E_j^p.
pub fn coalition_covers<'a>(
    members: impl IntoIterator<Item = &'a Resources>,
    need: &Resources,
) -> bool {
    let total = sum_resources(members);
    total.iter().zip(need).all(|(have, want)| have >= want)
}

/// Sum of resource vectors (the left side of 2.6).
pub fn sum_resources<'a>(members: impl IntoIterator<Item = &'a Resources>) -> Resources {
    let mut total = [0.0; N_RESOURCES];
    for r in members {
        for (t, x) in total.iter_mut().zip(r) {
            *t += x;
        }
    }
    total
}

/// (2.7) compatibility E_i' ∩ E_j ≠ ∅, read for count vectors as "some type p that the robot
/// carries and the task needs" (spec 1.2 item 3).
pub fn compatible(robot: &Resources, task: &Resources) -> bool {
    robot
        .iter()
        .zip(task)
        .any(|(have, want)| *have > 0.0 && *want > 0.0)
}

/// The speed-capability rule: the robot is at least as fast as the task requires.
pub fn speed_capable(robot_speed: f64, task: &Task) -> bool {
    robot_speed >= task.min_robot_speed
}

/// q_ij of (3.16): robot i and task j match under the per-robot constraints a single robot can
/// check on its own, (2.5) for the straight-line trip, (2.7) and the speed capability. The
/// coalition constraint (2.6) is the auctioneer's (spec 3.3 [INFERRED]).
pub fn feasible(robot: &Robot, task: &Task) -> bool {
    let trip = (task.position - robot.position).norm();
    mileage_ok(robot, trip)
        && compatible(&robot.resources, &task.resources)
        && speed_capable(robot.speed, task)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) fn robot(id: RobotId, x: f64, y: f64, resources: Resources) -> Robot {
        Robot {
            id,
            position: Vec2::new(x, y),
            heading: 0.0,
            resources,
            matching: vec![0.2; 5],
            speed: 0.8,
            turn_rate: 6.0,
            max_mileage: f64::INFINITY,
            travelled: 0.0,
        }
    }

    pub(crate) fn task(id: TaskId, x: f64, y: f64, resources: Resources, l: usize) -> Task {
        Task {
            id,
            position: Vec2::new(x, y),
            resources,
            required_robots: l,
            reward_cap: 500.0,
            speed: 1.0,
            min_robot_speed: 0.0,
        }
    }

    #[test]
    fn mileage_limit_2_5() {
        let mut r = robot(1, 0.0, 0.0, [1.0; 6]);
        r.max_mileage = 10.0;
        r.travelled = 7.0;
        assert!(mileage_ok(&r, 3.0));
        assert!(!mileage_ok(&r, 3.01));
        let t = task(1, 4.0, 0.0, [1.0; 6], 1);
        assert!(!feasible(&r, &t), "a 4 km trip with 3 km left breaks (2.5)");
    }

    #[test]
    fn coalition_resources_2_6_on_table_3_1_t1() {
        // Spec 10.1: {R1, R2, R15} sums to {20,15,25,23,34,31} >= T1's {10,9,14,15,18,15}.
        let r1 = [3.0, 2.0, 5.0, 6.0, 8.0, 7.0];
        let r2 = [14.0, 11.0, 15.0, 11.0, 18.0, 17.0];
        let r15 = [3.0, 2.0, 5.0, 6.0, 8.0, 7.0];
        let t1 = [10.0, 9.0, 14.0, 15.0, 18.0, 15.0];
        assert_eq!(
            sum_resources([&r1, &r2, &r15]),
            [20.0, 15.0, 25.0, 23.0, 34.0, 31.0]
        );
        assert!(coalition_covers([&r1, &r2, &r15], &t1));
        // R1 + R15 alone: type 1 is 6 < 10.
        assert!(!coalition_covers([&r1, &r15], &t1));
    }

    #[test]
    fn compatibility_2_7_needs_one_shared_type() {
        let t = [0.0, 0.0, 3.0, 0.0, 0.0, 0.0];
        assert!(!compatible(&[1.0, 1.0, 0.0, 1.0, 1.0, 1.0], &t));
        assert!(compatible(&[0.0, 0.0, 1.0, 0.0, 0.0, 0.0], &t));
    }

    #[test]
    fn speed_capability_rule() {
        let mut t = task(3, 0.0, 0.0, [1.0; 6], 4);
        t.min_robot_speed = 0.7;
        let mut r = robot(10, 1.0, 0.0, [1.0; 6]);
        r.speed = 0.69;
        assert!(!feasible(&r, &t));
        r.speed = 0.7;
        assert!(feasible(&r, &t));
    }

    #[test]
    fn matching_by_task_id() {
        let mut r = robot(1, 0.0, 0.0, [1.0; 6]);
        r.matching = vec![0.4, 0.1, 0.3, 0.1, 0.1];
        assert_eq!(r.matching(1), 0.4);
        assert_eq!(r.matching(3), 0.3);
        assert_eq!(r.matching(6), 0.0);
        assert_eq!(r.matching(0), 0.0);
    }
}
