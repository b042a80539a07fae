//! The score of thesis sec. 4.2.2: the time-decaying reward (4.12), the path utility with the
//! path cost (4.13)-(4.14) and the marginal gain of inserting a task (4.15).
//!
//! Choices where the thesis is silent (spec 12 item 8): t_(p_i) - t_o is the robot's own
//! travel time along the path (cumulative leg length / its speed) plus the hold times of the
//! earlier tasks of the path; waiting for the coalition's joint arrival is not known when a
//! robot bids, so it is not in the bid (dag.rs computes the joint schedule afterwards). d_ij is
//! the leg length, from the previous task of the path (or the robot's position for the first).

use super::model::{Robot, TaskBook, TaskId};
use super::params::CbcaParams;

/// One task's share of a path's utility: S_ij(p_i) = w1 r_ij(p_i) - w2 xi_ij.
#[derive(Clone, Debug, PartialEq)]
pub struct TaskScore {
    pub task: TaskId,
    /// d_ij, the leg length (km).
    pub distance: f64,
    /// t_(p_i) - t_o, when the robot would execute the task (time units).
    pub elapsed: f64,
    /// r_ij(p_i) = V_aj exp(-beta_j (t_(p_i) - t_o)) (4.12).
    pub reward: f64,
    /// xi_ij = d_ij gamma_i (4.14).
    pub cost: f64,
    /// w1 r_ij - w2 xi_ij, this task's term of (4.13).
    pub score: f64,
}

/// S_i(p_i) (4.13) with its per-task terms.
#[derive(Clone, Debug, PartialEq)]
pub struct PathScore {
    pub total: f64,
    pub tasks: Vec<TaskScore>,
}

/// S_i(p_i) of (4.13) for `path`, executed from the robot's position at t_o. Tasks missing from
/// the book are skipped (a caller checks the path first).
pub fn path_score(
    robot: &Robot,
    path: &[TaskId],
    book: &TaskBook,
    params: &CbcaParams,
) -> PathScore {
    let mut at = robot.position;
    let mut elapsed = 0.0;
    let mut tasks = Vec::with_capacity(path.len());
    let mut total = 0.0;
    for &j in path {
        let Some(t) = book.get(&j) else { continue };
        let distance = (t.pos() - at).norm();
        elapsed += distance / robot.speed;
        let reward = t.value * (-t.beta * elapsed).exp(); // (4.12)
        let cost = distance * robot.gamma; // (4.14)
        let score = params.w1 * reward - params.w2 * cost; // a term of (4.13)
        total += score;
        tasks.push(TaskScore {
            task: j,
            distance,
            elapsed,
            reward,
            cost,
            score,
        });
        // Principle 4: the robot holds the target before it leaves for the next one.
        elapsed += t.hold_time;
        at = t.pos();
    }
    PathScore { total, tasks }
}

/// The best insertion of a task into a path (4.15).
#[derive(Clone, Debug, PartialEq)]
pub struct Insertion {
    /// n: the task goes before the n-th entry of p_i (n = |p_i| appends).
    pub position: usize,
    /// c_ij = S_i(p_i ⊕_n {j}) - S_i(p_i).
    pub gain: f64,
    /// S_i(p_i ⊕_n {j}).
    pub new_score: f64,
}

/// p_i ⊕_n {j}: `path` with `j` inserted at `n`.
pub fn insert_at(path: &[TaskId], n: usize, j: TaskId) -> Vec<TaskId> {
    let mut p = Vec::with_capacity(path.len() + 1);
    p.extend_from_slice(&path[..n]);
    p.push(j);
    p.extend_from_slice(&path[n..]);
    p
}

/// The marginal gain c_ij[b_i] of (4.15): max over the insertion positions n whose path
/// `allowed` accepts (the constraints of sec. 4.1) of S_i(p_i ⊕_n {j}) - S_i(p_i). `None` when
/// j is already in the path (the thesis's c = 0) or no position is allowed. Ties between
/// positions go to the earliest.
pub fn marginal_gain(
    robot: &Robot,
    path: &[TaskId],
    j: TaskId,
    book: &TaskBook,
    params: &CbcaParams,
    allowed: impl Fn(&[TaskId]) -> bool,
) -> Option<Insertion> {
    if path.contains(&j) || !book.contains_key(&j) {
        return None;
    }
    let base = path_score(robot, path, book, params).total;
    let mut best: Option<Insertion> = None;
    for n in 0..=path.len() {
        let candidate = insert_at(path, n, j);
        if !allowed(&candidate) {
            continue;
        }
        let new_score = path_score(robot, &candidate, book, params).total;
        let gain = new_score - base;
        if best.as_ref().is_none_or(|b| gain > b.gain) {
            best = Some(Insertion {
                position: n,
                gain,
                new_score,
            });
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cbca::scenario::tests::example;

    fn ex1() -> (Vec<Robot>, TaskBook, CbcaParams) {
        let s = example(1);
        let book = s.task_book().unwrap();
        // The hand computations below take hold time 1 (the default) and speed 1.
        assert!(book.values().all(|t| t.hold_time == 1.0));
        (s.robots().unwrap(), book, s.params)
    }

    #[test]
    fn single_task_scores_of_table_rows_by_hand() {
        let (robots, book, params) = ex1();
        // R2 (1.28, 2.58), gamma 0.6 -> T1 (2.28, 2.56), V_a 200, beta 0.52, speed 1, w1 = w2 = 1:
        // d = sqrt(1.00^2 + 0.02^2) = 1.00020 km, t - t_o = 1.00020,
        // r = 200 e^(-0.52 * 1.00020) = 200 * 0.594459 = 118.8917,
        // xi = 0.6 * 1.00020 = 0.60012, S = 118.8917 - 0.6001 = 118.2916.
        let s = path_score(&robots[1], &[0], &book, &params);
        assert!((s.tasks[0].distance - 1.00020).abs() < 1e-5);
        assert!((s.tasks[0].reward - 118.8917).abs() < 1e-3);
        assert!((s.tasks[0].cost - 0.60012).abs() < 1e-5);
        assert!((s.total - 118.2916).abs() < 1e-3);
        // R3 (2.46, 1.86), gamma 0.7 -> T2 (4.89, 0.95), V_a 300, beta 0.63:
        // d = sqrt(2.43^2 + 0.91^2) = sqrt(5.9049 + 0.8281) = 2.59480,
        // r = 300 e^(-0.63 * 2.59480) = 300 * 0.195006 = 58.5018, xi = 0.7 * 2.59480 = 1.81636,
        // S = 56.6854.
        let s = path_score(&robots[2], &[1], &book, &params);
        assert!((s.total - 56.6854).abs() < 1e-3);
        // Weights: w1 = 2, w2 = 3 on R3 -> T2: 2 * 58.5018 - 3 * 1.81636 = 111.5544.
        let heavy = CbcaParams {
            w1: 2.0,
            w2: 3.0,
            ..params.clone()
        };
        assert!((path_score(&robots[2], &[1], &book, &heavy).total - 111.5544).abs() < 1e-3);
    }

    #[test]
    fn marginal_gain_takes_the_best_insertion_by_hand() {
        let (robots, book, params) = ex1();
        let r3 = &robots[2];
        // R3 -> T1 (2.28, 2.56): d = sqrt(0.18^2 + 0.70^2) = 0.72277, r = 200 e^(-0.52 * 0.72277)
        // = 137.3422, xi = 0.50594, S([T1]) = 136.8363.
        let base = path_score(r3, &[0], &book, &params).total;
        assert!((base - 136.8363).abs() < 1e-3);
        // [T1, T2]: T1 as above; T1 -> T2 leg sqrt(2.61^2 + 1.61^2) = 3.06663, T2 at
        // t = 0.72277 + 1 (hold) + 3.06663 = 4.78940: 300 e^(-0.63 * 4.78940) - 0.7 * 3.06663
        // = 14.6796 - 2.1466 = 12.5330; S = 149.3693, gain +12.5330.
        // [T2, T1]: T2 first (S_T2 = 56.6854), then T1 at 2.59480 + 1 + 3.06663 = 6.66143:
        // 200 e^(-0.52 * 6.66143) - 0.7 * 3.06663 = 6.2612 - 2.1466 = 4.1146; S = 60.8000,
        // gain -76.0363. So (4.15) picks n = 1 (append), gain 12.5330.
        let ins = marginal_gain(r3, &[0], 1, &book, &params, |_| true).unwrap();
        assert_eq!(ins.position, 1);
        assert!((ins.gain - 12.5330).abs() < 1e-3);
        assert!((ins.new_score - 149.3693).abs() < 1e-3);
        // Only the front position allowed: the worse one, gain -76.0363.
        let front = marginal_gain(r3, &[0], 1, &book, &params, |p| p[0] == 1).unwrap();
        assert_eq!(front.position, 0);
        assert!((front.gain + 76.0363).abs() < 1e-3);
        // A task already in the path: c = 0 of (4.15), no insertion.
        assert!(marginal_gain(r3, &[0], 0, &book, &params, |_| true).is_none());
        // Nothing allowed: none.
        assert!(marginal_gain(r3, &[0], 1, &book, &params, |_| false).is_none());
    }

    #[test]
    fn reward_decays_with_beta_and_time() {
        let (robots, mut book, params) = ex1();
        let r10 = &robots[9];
        // R10 (0.75, 1.68) -> T1: d = 1.76502, S = 200 e^(-0.52 * 1.76502) - 0.5 * 1.76502
        // = 79.8785 - 0.8825 = 78.9960; a nearer robot (R3, above 136.84) scores higher.
        let s = path_score(r10, &[0], &book, &params).total;
        assert!((s - 78.9960).abs() < 1e-3);
        // A slower decay raises it; beta = 0 leaves V_a - cost = 200 - 0.8825.
        book.get_mut(&0).unwrap().beta = 0.0;
        assert!((path_score(r10, &[0], &book, &params).total - 199.1175).abs() < 1e-3);
    }
}
