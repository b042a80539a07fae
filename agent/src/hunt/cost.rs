//! The cost models of the improved auction (thesis sec. 3.1): the robot's cost C_ij (3.9)-(3.10)
//! and utility y_ij (3.8), (3.16), and the auctioneer's cost c_ij (3.12).

use crate::hunt::model::{feasible, Robot, Task};
use crate::hunt::params::HuntParams;

/// E_ij, the resources robot i spends on target j (3.9). [chosen] The thesis never says how it is
/// computed (spec 3.3): the robot's share of the requirement it can cover,
/// E_ij = sum_p min(E_i'^p, E_j^p / L_j), in resource units.
pub fn resource_spent(robot: &Robot, task: &Task) -> f64 {
    let l = task.required_robots.max(1) as f64;
    robot
        .resources
        .iter()
        .zip(&task.resources)
        .map(|(have, need)| have.min(need / l))
        .sum()
}

/// v_j - v_i, floored at `speed_gap_floor` (the thesis assumes robots slower than targets; see
/// `HuntParams::speed_gap_floor`).
pub fn speed_gap(robot_speed: f64, task_speed: f64, p: &HuntParams) -> f64 {
    (task_speed - robot_speed).max(p.speed_gap_floor)
}

/// T'_ij = (r_e + r_s) / (2 (v_j - v_i) L_j), the expected time to form the encirclement once in
/// the effective range (3.10).
pub fn encirclement_time(robot: &Robot, task: &Task, p: &HuntParams) -> f64 {
    let l = task.required_robots.max(1);
    (p.effective_range(l) + p.r_s) / (2.0 * speed_gap(robot.speed, task.speed, p) * l as f64)
}

/// d_ij / (v_j - v_i), the pursuit time term of (3.9).
pub fn pursuit_time(robot: &Robot, task: &Task, p: &HuntParams) -> f64 {
    (task.position - robot.position).norm() / speed_gap(robot.speed, task.speed, p)
}

/// C_ij = m1 E_ij + m2 T'_ij + m3 d_ij / (v_j - v_i), eq. (3.9).
pub fn robot_cost(robot: &Robot, task: &Task, p: &HuntParams) -> f64 {
    p.m1 * resource_spent(robot, task)
        + p.m2 * encirclement_time(robot, task, p)
        + p.m3 * pursuit_time(robot, task, p)
}

/// U_ij^r = z_j^r g_ij, eq. (3.8): the reward is the task's current one, the same for every
/// bidder (spec 3.2 [INFERRED]).
pub fn benefit(robot: &Robot, task: &Task, reward: f64) -> f64 {
    reward * robot.matching(task.id)
}

/// y_ij^r of eq. (3.16): z_j^r g_ij - C_ij when robot and task match (q_ij = 1), `None` (the
/// thesis's -infinity) otherwise.
pub fn bid_value(robot: &Robot, task: &Task, reward: f64, p: &HuntParams) -> Option<f64> {
    feasible(robot, task).then(|| benefit(robot, task, reward) - robot_cost(robot, task, p))
}

/// c_rho_j = z_rho_j^r + f_rho_j, eq. (3.12): the reward paid plus the time cost f, "taken as
/// equivalent to the straight-line distance" (sec. 3.1.1), so f = d_ij in km.
pub fn auctioneer_cost(reward: f64, distance: f64) -> f64 {
    reward + distance
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hunt::scenario::tests::example_3a;
    use crate::hunt::scenario::HuntKernels;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() < tol
    }

    #[test]
    fn r1_on_t1_by_hand() {
        // Table 3.2 R1 (1.54, 6.88), E' = {3,2,5,6,8,7}, g_11 = 0.4, v = 0.8 (chosen);
        // Table 3.1 T1 (1.94, 9.11), E = {10,9,14,15,18,15}, L = 3, z_max = 520, v = 1.0.
        // d = sqrt(0.40^2 + 2.23^2) = sqrt(5.1329) = 2.265591
        // v_j - v_i = 0.2
        // E_ij = min(3,10/3) + min(2,3) + min(5,14/3) + min(6,5) + min(8,6) + min(7,5)
        //      = 3 + 2 + 4.666667 + 5 + 6 + 5 = 25.666667
        // T'   = (r_e + r_s) / (2 * 0.2 * 3) = (1.0 + 0.3) / 1.2 = 1.083333           (3.10)
        // C    = 0.2 * 25.666667 + 0.3 * 1.083333 + 0.5 * 2.265591 / 0.2
        //      = 5.133333 + 0.325 + 5.663977 = 11.122310                              (3.9)
        // z^1  = 0.8 * 520 = 416; y = 416 * 0.4 - 11.122310 = 155.277690          (3.11) (3.16)
        // c    = 416 + 2.265591 = 418.265591                                          (3.12)
        let h = example_3a();
        let p = HuntParams::default();
        let (r1, t1) = (&h.robots()[0], &h.tasks()[0]);
        assert!(close(resource_spent(r1, t1), 25.666667, 1e-6));
        assert!(close(encirclement_time(r1, t1, &p), 1.083333, 1e-6));
        assert!(close(robot_cost(r1, t1, &p), 11.122310, 1e-6));
        assert!(close(
            bid_value(r1, t1, 416.0, &p).unwrap(),
            155.277690,
            1e-6
        ));
        let d = (t1.position - r1.position).norm();
        assert!(close(auctioneer_cost(416.0, d), 418.265591, 1e-6));
    }

    #[test]
    fn r12_on_t4_by_hand() {
        // R12 (9.04, 2.56), E' = {8,6,8,4,7,9}, g_12,4 = 0.1, v = 0.75 (chosen);
        // T4 (7.21, 5.36), E = {9,10,12,8,12,6}, L = 5, z_max = 1350, v = 1.2.
        // d = sqrt(1.83^2 + 2.80^2) = sqrt(3.3489 + 7.84) = sqrt(11.1889) = 3.344981
        // v_j - v_i = 0.45; r_e = 1.0 * 3 / 5 = 0.6
        // E_ij = min(8,1.8) + min(6,2) + min(8,2.4) + min(4,1.6) + min(7,2.4) + min(9,1.2)
        //      = 1.8 + 2 + 2.4 + 1.6 + 2.4 + 1.2 = 11.4
        // T'   = (0.6 + 0.3) / (2 * 0.45 * 5) = 0.9 / 4.5 = 0.2
        // C    = 0.2 * 11.4 + 0.3 * 0.2 + 0.5 * 3.344981 / 0.45
        //      = 2.28 + 0.06 + 3.716646 = 6.056646
        // z^1  = 0.8 * 1350 = 1080; y = 108 - 6.056646 = 101.943354
        let h = example_3a();
        let p = HuntParams::default();
        let (r12, t4) = (&h.robots()[11], &h.tasks()[3]);
        assert!(close(resource_spent(r12, t4), 11.4, 1e-9));
        assert!(close(encirclement_time(r12, t4, &p), 0.2, 1e-9));
        assert!(close(robot_cost(r12, t4, &p), 6.056646, 1e-6));
        assert!(close(
            bid_value(r12, t4, 1080.0, &p).unwrap(),
            101.943354,
            1e-6
        ));
    }

    #[test]
    fn r10_cannot_bid_on_t3_speed_capability() {
        let h = example_3a();
        let p = HuntParams::default();
        assert_eq!(bid_value(&h.robots()[9], &h.tasks()[2], 656.0, &p), None);
        assert!(bid_value(&h.robots()[11], &h.tasks()[2], 656.0, &p).is_some());
    }

    #[test]
    fn faster_robot_gets_the_floor_not_a_negative_time() {
        let h = example_3a();
        let p = HuntParams::default();
        let mut r = h.robots()[0].clone();
        r.speed = 1.5; // faster than T1 (1.0)
        assert_eq!(speed_gap(r.speed, 1.0, &p), p.speed_gap_floor);
        assert!(robot_cost(&r, &h.tasks()[0], &p) > 0.0);
    }
}
