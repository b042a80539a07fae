//! Joint arrival without deadlock (thesis sec. 4.1, (4.6)-(4.8)). Every member of a task's
//! coalition must arrive before the task starts, so a robot may wait for the others at each of
//! its tasks. The plan is deadlock-free iff the task graph G(T, ε(A)) is a DAG (4.6), with the
//! targets as vertices (4.7) and an edge from each task of a robot's path to its next task
//! (4.8). With a DAG the joint schedule follows in topological order ([`joint_schedule`]).
//!
//! [`cycle_closer`] is our repair rule (the thesis only states the constraint): when the
//! robots' paths, as one robot knows them, form a cycle, the robot with the smallest id whose
//! path closes a cycle among the paths of robots with ids up to its own drops tasks; every robot
//! that knows the same paths names the same robot, so exactly one gives way.

use std::collections::{BTreeMap, BTreeSet};

use super::model::{Robot, RobotId, TaskBook, TaskId};

/// ε(A) of (4.8): (p_i(k), p_i(k+1)) for every robot's path.
pub fn task_edges<'a>(paths: impl IntoIterator<Item = &'a [TaskId]>) -> BTreeSet<(TaskId, TaskId)> {
    let mut edges = BTreeSet::new();
    for p in paths {
        for w in p.windows(2) {
            edges.insert((w[0], w[1]));
        }
    }
    edges
}

/// A topological order of the tasks appearing in `edges` and `vertices` (Kahn, smallest id
/// first), or `Err` with the tasks left on cycles.
pub fn topological_order(
    vertices: &BTreeSet<TaskId>,
    edges: &BTreeSet<(TaskId, TaskId)>,
) -> Result<Vec<TaskId>, Vec<TaskId>> {
    let mut all: BTreeSet<TaskId> = vertices.clone();
    for &(a, b) in edges {
        all.insert(a);
        all.insert(b);
    }
    let mut indegree: BTreeMap<TaskId, usize> = all.iter().map(|&v| (v, 0)).collect();
    for &(_, b) in edges {
        *indegree.get_mut(&b).expect("vertex") += 1;
    }
    let mut ready: BTreeSet<TaskId> = indegree
        .iter()
        .filter(|(_, d)| **d == 0)
        .map(|(v, _)| *v)
        .collect();
    let mut order = Vec::with_capacity(all.len());
    while let Some(v) = ready.pop_first() {
        order.push(v);
        for &(_, b) in edges.range((v, TaskId::MIN)..=(v, TaskId::MAX)) {
            let d = indegree.get_mut(&b).expect("vertex");
            *d -= 1;
            if *d == 0 {
                ready.insert(b);
            }
        }
    }
    if order.len() == all.len() {
        Ok(order)
    } else {
        let done: BTreeSet<TaskId> = order.into_iter().collect();
        Err(all.difference(&done).copied().collect())
    }
}

/// (4.6): the task graph of these paths is a DAG.
pub fn is_dag<'a>(paths: impl IntoIterator<Item = &'a [TaskId]>) -> bool {
    topological_order(&BTreeSet::new(), &task_edges(paths)).is_ok()
}

/// The repair rule: the smallest robot i such that the paths of robots 0..=i form a cycle
/// (`paths[i]` is robot i's path as known; empty when unknown). `None` for a DAG.
pub fn cycle_closer(paths: &[Vec<TaskId>]) -> Option<RobotId> {
    let mut edges = BTreeSet::new();
    for (i, p) in paths.iter().enumerate() {
        let before = edges.len();
        for w in p.windows(2) {
            edges.insert((w[0], w[1]));
        }
        if edges.len() > before && topological_order(&BTreeSet::new(), &edges).is_err() {
            return Some(i);
        }
    }
    None
}

/// The paths deadlock: their task graph has cycles through these tasks.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("deadlock: the task graph has a cycle through tasks {tasks:?} (4.6)")]
pub struct Deadlock {
    pub tasks: Vec<TaskId>,
}

/// When each task starts and ends under joint arrival, and how long each robot waits.
#[derive(Clone, Debug, PartialEq)]
pub struct Schedule {
    /// Task -> start time (the last member's arrival), relative to t_o.
    pub start: BTreeMap<TaskId, f64>,
    /// Task -> end of its hold.
    pub finish: BTreeMap<TaskId, f64>,
    /// Per robot, its arrival time at each task of its path.
    pub arrival: Vec<Vec<f64>>,
    /// Per robot, its total waiting time for the coalitions it joins.
    pub waiting: Vec<f64>,
}

/// The joint schedule of `paths` (robot i follows `paths[i]` from `robots[i].position` at its
/// speed): a task starts when its last member arrives and lasts its hold time; a member leaves
/// for its next task at the end of the hold. `Err` when (4.6) fails: then some robots would wait
/// for each other for ever.
pub fn joint_schedule(
    robots: &[Robot],
    paths: &[Vec<TaskId>],
    book: &TaskBook,
) -> Result<Schedule, Deadlock> {
    let edges = task_edges(paths.iter().map(|p| p.as_slice()));
    let vertices: BTreeSet<TaskId> = paths.iter().flatten().copied().collect();
    let order = topological_order(&vertices, &edges).map_err(|tasks| Deadlock { tasks })?;
    // Members of each task, with the index of the task in their path.
    let mut members: BTreeMap<TaskId, Vec<(RobotId, usize)>> = BTreeMap::new();
    for (i, p) in paths.iter().enumerate() {
        for (k, &j) in p.iter().enumerate() {
            members.entry(j).or_default().push((i, k));
        }
    }
    let mut arrival: Vec<Vec<f64>> = paths.iter().map(|p| vec![0.0; p.len()]).collect();
    let mut waiting = vec![0.0; paths.len()];
    let mut start = BTreeMap::new();
    let mut finish = BTreeMap::new();
    for j in order {
        let Some(ms) = members.get(&j) else { continue };
        let task = &book[&j];
        let mut t_start: f64 = 0.0;
        for &(i, k) in ms {
            // The previous task precedes j in the order, so its finish is known.
            let (from, leave) = if k == 0 {
                (robots[i].position, 0.0)
            } else {
                let prev = paths[i][k - 1];
                (book[&prev].pos(), finish[&prev])
            };
            let t = leave + (task.pos() - from).norm() / robots[i].speed;
            arrival[i][k] = t;
            t_start = t_start.max(t);
        }
        for &(i, k) in ms {
            waiting[i] += t_start - arrival[i][k];
        }
        start.insert(j, t_start);
        finish.insert(j, t_start + task.hold_time);
    }
    Ok(Schedule {
        start,
        finish,
        arrival,
        waiting,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cbca::model::tests::{robot, task};

    fn book() -> TaskBook {
        // T1 at (0, 3), T2 at (4, 3), T3 at (4, 0); hold 1.
        [[0.0, 3.0], [4.0, 3.0], [4.0, 0.0]]
            .iter()
            .enumerate()
            .map(|(j, p)| (j, task(j, *p, [1.0; 6], 2)))
            .collect()
    }

    #[test]
    fn crossing_orders_are_a_cycle() {
        // R1 does T1 then T2, R2 does T2 then T1: R1 waits at T1 for R2, who waits at T2 for R1.
        let paths = vec![vec![0, 1], vec![1, 0]];
        assert!(!is_dag(paths.iter().map(|p| p.as_slice())));
        let robots = vec![
            robot(0, [0.0, 0.0], [1.0; 6]),
            robot(1, [4.0, 0.0], [1.0; 6]),
        ];
        assert_eq!(
            joint_schedule(&robots, &paths, &book()),
            Err(Deadlock { tasks: vec![0, 1] })
        );
        // R2 (index 1) closes the cycle; R1's path alone is fine.
        assert_eq!(cycle_closer(&paths), Some(1));
        // A longer cycle T1 -> T2 -> T3 -> T1 over three robots, closed by the third.
        let three = vec![vec![0, 1], vec![], vec![1, 2], vec![2, 0]];
        assert_eq!(cycle_closer(&three), Some(3));
        assert!(is_dag(three[..3].iter().map(|p| p.as_slice())));
    }

    #[test]
    fn same_orders_are_a_dag_and_the_schedule_waits_by_hand() {
        // R1 from (0, 0): T1 (3 km) then T2 (4 km). R2 from (4, 0): T1 (5 km) then T2 (4 km).
        let paths = vec![vec![0, 1], vec![0, 1]];
        assert!(is_dag(paths.iter().map(|p| p.as_slice())));
        assert_eq!(cycle_closer(&paths), None);
        let mut robots = vec![
            robot(0, [0.0, 0.0], [1.0; 6]),
            robot(1, [4.0, 0.0], [1.0; 6]),
        ];
        robots[1].speed = 2.0;
        let s = joint_schedule(&robots, &paths, &book()).unwrap();
        // T1: R1 arrives at 3, R2 at 5 / 2 = 2.5; starts at 3, ends at 4 (hold 1); R2 waits 0.5.
        // T2: R1 arrives at 4 + 4 = 8, R2 at 4 + 4 / 2 = 6; starts 8, ends 9; R2 waits 2.
        assert_eq!(s.arrival, vec![vec![3.0, 8.0], vec![2.5, 6.0]]);
        assert_eq!(s.start[&0], 3.0);
        assert_eq!(s.finish[&0], 4.0);
        assert_eq!(s.start[&1], 8.0);
        assert_eq!(s.finish[&1], 9.0);
        assert_eq!(s.waiting, vec![0.0, 2.5]);
    }

    #[test]
    fn topological_order_lists_isolated_tasks() {
        let edges: BTreeSet<_> = [(2, 0)].into_iter().collect();
        let vertices: BTreeSet<_> = [1].into_iter().collect();
        assert_eq!(topological_order(&vertices, &edges), Ok(vec![1, 2, 0]));
    }
}
