//! The model of thesis 003 chapter 4, sec. 4.1 (docs/hunting.md sections 1.1, 1.2, 4.1): robots
//! with z = 6 resource types, a task limit l_i and a mileage budget; tasks (targets) with a
//! required resource vector E_j, a robot count L_j, an initial value V_a, a decay beta_j and a hold
//! time; and the constraints a path must meet: mileage (2.5), compatibility (2.7), resource budget
//! with consumption (4.5). The coalition resource rule (2.6) is a check on a coalition
//! ([`coverage_shortfall`]); the deadlock rule (4.6)-(4.8) is in `dag.rs`.
//!
//! Identifiers are 0-based indices: robot `i` is the thesis's R_{i+1}, task `j` its T_{j+1}
//! ([`robot_label`], [`task_label`]). A smaller index is a smaller ID (the tie rule of 4.16).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use swarm::geometry::Vec2;

use super::params::{CbcaParams, Consumption};

/// z, the number of resource types (every table of the thesis has 6).
pub const RESOURCE_TYPES: usize = 6;

/// A resource vector E (2.3)/(2.4): units of each of the z types.
pub type Resources = [f64; RESOURCE_TYPES];

/// Robot index (0-based; R_{i+1} in the thesis).
pub type RobotId = usize;
/// Task (target) index (0-based; T_{j+1} in the thesis).
pub type TaskId = usize;

/// The tasks a robot knows, by id (a BTreeMap: iterated in id order).
pub type TaskBook = BTreeMap<TaskId, Task>;

/// "R3" for robot index 2.
pub fn robot_label(i: RobotId) -> String {
    format!("R{}", i + 1)
}

/// "T1" for task index 0.
pub fn task_label(j: TaskId) -> String {
    format!("T{}", j + 1)
}

/// Robot R_i = <X_i, E_i', l_i> (2.1), with the chapter 4 additions.
#[derive(Clone, Debug, PartialEq)]
pub struct Robot {
    pub id: RobotId,
    /// X_i (km), where it plans from.
    pub position: Vec2,
    /// gamma_i, the path-cost coefficient of (4.14).
    pub gamma: f64,
    /// E_i', the resources it carries (2.4), before any consumption.
    pub resources: Resources,
    /// Its speed (km per time unit), for the execution time t_(p_i) of (4.12).
    pub speed: f64,
    /// l_i, the most tasks it may accept (4.2).
    pub max_tasks: usize,
    /// d^c_{max,i} of (2.5), the remaining range when it plans (km).
    pub mileage_budget: f64,
}

/// Target T_j = <X_j, E_j, L_j, V_a> (2.2), with the chapter 4 decay and hold time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Task {
    pub id: TaskId,
    /// X_j (km).
    pub position: [f64; 2],
    /// V_aj, the initial value (4.12).
    pub value: f64,
    /// E_j, the required resources (2.3).
    pub required: Resources,
    /// beta_j in [0, 1], the time discount of (4.12).
    pub beta: f64,
    /// L_j, the robots it needs (4.3) and, by principle 3, the most it accepts.
    pub robots_needed: usize,
    /// Principle 4: how long its coalition must hold the encirclement after capture (time
    /// units); the robots' next tasks start after it.
    pub hold_time: f64,
}

impl Task {
    pub fn pos(&self) -> Vec2 {
        Vec2::new(self.position[0], self.position[1])
    }
}

/// (2.7), read for count vectors: some type p that both carry (a^p > 0 and b^p > 0).
pub fn overlaps(a: &Resources, b: &Resources) -> bool {
    a.iter().zip(b).any(|(x, y)| *x > 0.0 && *y > 0.0)
}

/// What robot i uses up on task j (4.5) given what it has left, under the chosen rule.
pub fn consumption(remaining: &Resources, task: &Task, rule: Consumption) -> Resources {
    let mut used = [0.0; RESOURCE_TYPES];
    for p in 0..RESOURCE_TYPES {
        let want = match rule {
            Consumption::FairShare => task.required[p] / task.robots_needed.max(1) as f64,
            Consumption::FullNeed => task.required[p],
        };
        used[p] = want.min(remaining[p]).max(0.0);
    }
    used
}

/// Why a path is not allowed (the constraints of sec. 4.1 that one robot can check alone).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Infeasible {
    /// (2.5): the path is longer than the remaining range.
    #[error("path of {length:.3} km exceeds the mileage budget {budget:.3} km (2.5)")]
    Mileage { length: f64, budget: f64 },
    /// (2.7) on what is left after the earlier tasks of the path: nothing the task needs.
    #[error("no resource left that {} needs (2.7 after 4.5)", task_label(*.task))]
    Incompatible { task: TaskId },
    /// (4.5): the consumption along the path exceeds the robot's resources (only possible
    /// with a rule that does not cap use at what is left).
    #[error("consumption exceeds the resources carried (4.5)")]
    Resources,
    /// More than l_i tasks (4.2).
    #[error("more than l_i = {max} tasks (4.2)")]
    TooManyTasks { max: usize },
    /// A task of the path is not in the book.
    #[error("unknown task {}", task_label(*.task))]
    UnknownTask { task: TaskId },
}

/// Length (km) of the legs of a path from `start`: start -> p_1 -> p_2 ... (the mileage of 2.5).
pub fn path_length(start: Vec2, path: &[TaskId], book: &TaskBook) -> f64 {
    let mut at = start;
    let mut len = 0.0;
    for j in path {
        if let Some(t) = book.get(j) {
            len += (t.pos() - at).norm();
            at = t.pos();
        }
    }
    len
}

/// Checks a path against (4.2), (2.5), (2.7) and (4.5); returns the resources left at its end.
pub fn check_path(
    robot: &Robot,
    path: &[TaskId],
    book: &TaskBook,
    params: &CbcaParams,
) -> Result<Resources, Infeasible> {
    if path.len() > robot.max_tasks {
        return Err(Infeasible::TooManyTasks {
            max: robot.max_tasks,
        });
    }
    let mut left = robot.resources;
    let mut used_total = [0.0; RESOURCE_TYPES];
    for &j in path {
        let task = book.get(&j).ok_or(Infeasible::UnknownTask { task: j })?;
        if !overlaps(&left, &task.required) {
            return Err(Infeasible::Incompatible { task: j });
        }
        let used = consumption(&left, task, params.consumption);
        for p in 0..RESOURCE_TYPES {
            left[p] -= used[p];
            used_total[p] += used[p];
        }
    }
    // (4.5) E(p_i) <= E_i', kept as an explicit check: both rules cap use at what is left,
    // so this holds by construction; a future rule that does not would be caught here.
    if used_total
        .iter()
        .zip(&robot.resources)
        .any(|(u, e)| *u > *e + 1e-9)
    {
        return Err(Infeasible::Resources);
    }
    let length = path_length(robot.position, path, book);
    if length > robot.mileage_budget + 1e-12 {
        return Err(Infeasible::Mileage {
            length,
            budget: robot.mileage_budget,
        });
    }
    Ok(left)
}

/// (2.6) for a coalition: per type, how much the members' summed resources fall short of E_j
/// (all zeros when the coalition covers the task).
pub fn coverage_shortfall(members: &[&Resources], task: &Task) -> Resources {
    let mut short = [0.0; RESOURCE_TYPES];
    for (p, s) in short.iter_mut().enumerate() {
        let have: f64 = members.iter().map(|r| r[p]).sum();
        *s = (task.required[p] - have).max(0.0);
    }
    short
}

/// True when (2.6) holds: the coalition's summed resources cover E_j in every type.
pub fn covers(members: &[&Resources], task: &Task) -> bool {
    coverage_shortfall(members, task).iter().all(|s| *s == 0.0)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub fn task(id: TaskId, pos: [f64; 2], required: Resources, needed: usize) -> Task {
        Task {
            id,
            position: pos,
            value: 100.0,
            required,
            beta: 0.5,
            robots_needed: needed,
            hold_time: 1.0,
        }
    }

    pub fn robot(id: RobotId, pos: [f64; 2], resources: Resources) -> Robot {
        Robot {
            id,
            position: Vec2::new(pos[0], pos[1]),
            gamma: 0.5,
            resources,
            speed: 1.0,
            max_tasks: 3,
            mileage_budget: 20.0,
        }
    }

    /// Tasks needing 1 unit of every type, ids 0..: each (position, L_j, V_a).
    pub fn unit_tasks(rows: &[([f64; 2], usize, f64)]) -> Vec<Task> {
        rows.iter()
            .enumerate()
            .map(|(j, &(pos, needed, value))| Task {
                value,
                ..task(j, pos, [1.0; RESOURCE_TYPES], needed)
            })
            .collect()
    }

    /// Robots with 1 unit of every type, ids 0.., at the given positions.
    pub fn unit_robots(positions: &[[f64; 2]]) -> Vec<Robot> {
        positions
            .iter()
            .enumerate()
            .map(|(i, &pos)| robot(i, pos, [1.0; RESOURCE_TYPES]))
            .collect()
    }

    fn book(tasks: Vec<Task>) -> TaskBook {
        tasks.into_iter().map(|t| (t.id, t)).collect()
    }

    #[test]
    fn fair_share_consumption_caps_at_what_is_left() {
        let t = task(0, [0.0, 0.0], [9.0, 3.0, 0.0, 6.0, 3.0, 3.0], 3);
        // Shares E_j / L_j = {3, 1, 0, 2, 1, 1}; the robot has {5, 0.5, 1, 1, 4, 0}.
        let used = consumption(&[5.0, 0.5, 1.0, 1.0, 4.0, 0.0], &t, Consumption::FairShare);
        assert_eq!(used, [3.0, 0.5, 0.0, 1.0, 1.0, 0.0]);
        let full = consumption(&[5.0, 0.5, 1.0, 1.0, 4.0, 0.0], &t, Consumption::FullNeed);
        assert_eq!(full, [5.0, 0.5, 0.0, 1.0, 3.0, 0.0]);
    }

    #[test]
    fn path_checks_mileage_and_resources() {
        let params = CbcaParams {
            consumption: Consumption::FullNeed,
            ..CbcaParams::default()
        };
        let b = book(vec![
            task(0, [3.0, 4.0], [2.0, 0.0, 0.0, 0.0, 0.0, 0.0], 1),
            task(1, [3.0, 0.0], [1.0, 0.0, 0.0, 0.0, 0.0, 0.0], 1),
            task(2, [0.0, 1.0], [0.0, 1.0, 0.0, 0.0, 0.0, 0.0], 1),
        ]);
        let mut r = robot(0, [0.0, 0.0], [2.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        // Task 0 alone: 5 km, uses both units of type 1.
        assert_eq!(
            check_path(&r, &[0], &b, &params),
            Ok([0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
        );
        // Then task 1 needs type 1, nothing left: (2.7) after (4.5).
        assert_eq!(
            check_path(&r, &[0, 1], &b, &params),
            Err(Infeasible::Incompatible { task: 1 })
        );
        // Task 2 needs type 2 the robot never had.
        assert_eq!(
            check_path(&r, &[2], &b, &params),
            Err(Infeasible::Incompatible { task: 2 })
        );
        // Mileage: task 1 then task 0 is 3 + 4 = 7 km.
        r.resources[0] = 5.0;
        r.mileage_budget = 6.5;
        assert!(matches!(
            check_path(&r, &[1, 0], &b, &params),
            Err(Infeasible::Mileage { length, .. }) if (length - 7.0).abs() < 1e-12
        ));
        r.mileage_budget = 7.0;
        assert!(check_path(&r, &[1, 0], &b, &params).is_ok());
        r.max_tasks = 1;
        assert_eq!(
            check_path(&r, &[1, 0], &b, &params),
            Err(Infeasible::TooManyTasks { max: 1 })
        );
    }

    #[test]
    fn coverage_of_a_coalition() {
        let t = task(0, [0.0, 0.0], [10.0, 9.0, 5.0, 5.0, 12.0, 8.0], 3);
        let a = [4.0, 5.0, 4.0, 3.0, 2.0, 1.0];
        let b = [5.0, 6.0, 2.0, 5.0, 6.0, 2.0];
        // a + b = {9, 11, 6, 8, 8, 3}: short {1, 0, 0, 0, 4, 5}.
        assert_eq!(
            coverage_shortfall(&[&a, &b], &t),
            [1.0, 0.0, 0.0, 0.0, 4.0, 5.0]
        );
        assert!(!covers(&[&a, &b], &t));
        let c = [3.0, 2.0, 5.0, 6.0, 8.0, 7.0];
        assert!(covers(&[&a, &b, &c], &t));
    }
}
