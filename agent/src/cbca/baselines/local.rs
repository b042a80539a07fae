//! The baselines under the information grouped CBCA has (issue 18's fair comparison, docs/
//! hunting.md 14.4): instead of seeing every robot and every target, each temporary group
//! (the components of the `params.comm_radius_km` radio graph, as CBCA's, grouping.rs) runs the
//! method on its own members and on the targets they know at the start (their detections plus
//! the undetected targets they are nearest to: `PriorInfo::DetectionPlusNearest`, CBCA's
//! prior). Groups that then claim a common target would meet at it: they merge, pool what they
//! know and run the method again (CBCA's `merge_on_conflict`, compare.rs), until no target is
//! claimed by two groups. Inside a group the method sees the whole group (Sujit et al.'s own
//! range limit is the group itself, so its radius is lifted inside it).
//!
//! Messages add up over every run of every group.

use std::collections::{BTreeMap, BTreeSet};

use swarm::geometry::Vec2;

use super::super::grouping::{robot_knowledge, temporary_groups, PriorInfo};
use super::super::model::{Robot, RobotId, Task, TaskBook, TaskId};
use super::super::params::CbcaParams;
use super::Allocation;

/// A baseline's allocation function (`sujit::allocate`, `welfare::allocate`,
/// `contract_net::allocate`).
pub type Allocator = fn(&[Robot], &TaskBook, &CbcaParams) -> Allocation;

/// `allocate` run group by group (see the module doc). Returns the allocation and the number of
/// merge steps.
pub fn allocate_local(
    allocate: Allocator,
    robots: &[Robot],
    tasks: &[Task],
    params: &CbcaParams,
) -> (Allocation, usize) {
    let n = robots.len();
    let pos: Vec<Vec2> = robots.iter().map(|r| r.position).collect();
    let knowledge = robot_knowledge(
        &pos,
        tasks,
        params.detection_radius_km,
        PriorInfo::DetectionPlusNearest,
    );
    let mut groups = temporary_groups(&pos, params.comm_radius_km);
    let inside = CbcaParams {
        comm_radius_km: f64::INFINITY,
        ..params.clone()
    };
    let mut messages = 0;
    let mut merges = 0;
    loop {
        let mut alloc = Allocation::empty(n);
        for g in &groups {
            let known: BTreeSet<TaskId> = g.iter().flat_map(|&i| knowledge[i].clone()).collect();
            let book: TaskBook = tasks
                .iter()
                .filter(|t| known.contains(&t.id))
                .map(|t| (t.id, t.clone()))
                .collect();
            let sub: Vec<Robot> = g
                .iter()
                .enumerate()
                .map(|(k, &i)| Robot {
                    id: k,
                    ..robots[i].clone()
                })
                .collect();
            let a = allocate(&sub, &book, &inside);
            for (k, &i) in g.iter().enumerate() {
                alloc.paths[i] = a.paths[k].clone();
            }
            messages += a.messages;
        }
        // Groups claiming a common target merge (union-find over group indices).
        let mut parent: Vec<usize> = (0..groups.len()).collect();
        fn root(p: &mut [usize], g: usize) -> usize {
            let mut r = g;
            while p[r] != r {
                r = p[r];
            }
            p[g] = r;
            r
        }
        let mut claimed: BTreeMap<TaskId, usize> = BTreeMap::new();
        let mut merged = false;
        for (gi, g) in groups.iter().enumerate() {
            for &i in g {
                for &j in &alloc.paths[i] {
                    match claimed.get(&j) {
                        None => {
                            claimed.insert(j, gi);
                        }
                        Some(&other) => {
                            let (a, b) = (root(&mut parent, other), root(&mut parent, gi));
                            if a != b {
                                parent[a.max(b)] = a.min(b);
                                merged = true;
                            }
                        }
                    }
                }
            }
        }
        if !merged {
            alloc.messages = messages;
            return (alloc, merges);
        }
        merges += 1;
        let mut by_root: BTreeMap<usize, Vec<RobotId>> = BTreeMap::new();
        for (gi, g) in groups.iter().enumerate() {
            let r = root(&mut parent, gi);
            by_root.entry(r).or_default().extend(g.iter().copied());
        }
        groups = by_root
            .into_values()
            .map(|mut g| {
                g.sort_unstable();
                g
            })
            .collect();
        groups.sort();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cbca::model::tests::{robot, task};

    #[test]
    fn groups_plan_apart_and_merge_on_a_shared_target() {
        // T1 at (0, 0) and T2 at (6, 0), both L = 2, needing 1 a type. Group A = {R1, R2} near
        // T1 (1 km apart), group B = {R3, R4} near T2 (1 km apart), 4+ km between the groups:
        // each knows only its own target (detections within 1.2 km) and takes it. No shared
        // target: no merge, each target by its own group.
        let tasks = vec![
            task(0, [0.0, 0.0], [1.0; 6], 2),
            task(1, [6.0, 0.0], [1.0; 6], 2),
        ];
        let robots = vec![
            robot(0, [0.0, 0.5], [1.0; 6]),
            robot(1, [0.0, -0.5], [1.0; 6]),
            robot(2, [6.0, 0.5], [1.0; 6]),
            robot(3, [6.0, -0.5], [1.0; 6]),
        ];
        let p = CbcaParams::default();
        let (a, merges) = allocate_local(super::super::contract_net::allocate, &robots, &tasks, &p);
        assert_eq!(a.paths, vec![vec![0], vec![0], vec![1], vec![1]]);
        assert_eq!(merges, 0);
        // Global information: the contract net sees all four and both targets: the same here.
        let book: TaskBook = tasks.iter().map(|t| (t.id, t.clone())).collect();
        let g = super::super::contract_net::allocate(&robots, &book, &p);
        assert_eq!(g.paths, a.paths);
        // Now group A sits at x = 2 and group B at x = 4 (2 km apart: two groups), T2 at
        // (3, 0) between them, 1.12 km from every robot: both groups detect it. T1 at (0, 0) is
        // 2.06 km from A, undetected, and R1 is its nearest robot (tie with R2: the smaller id),
        // so A knows T1 and T2, B knows T2. Both groups take T2: they merge and plan again as
        // one group, which then knows both targets: the global instance.
        let tasks = vec![
            task(0, [0.0, 0.0], [1.0; 6], 2),
            task(1, [3.0, 0.0], [1.0; 6], 2),
        ];
        let robots = vec![
            robot(0, [2.0, 0.5], [1.0; 6]),
            robot(1, [2.0, -0.5], [1.0; 6]),
            robot(2, [4.0, 0.5], [1.0; 6]),
            robot(3, [4.0, -0.5], [1.0; 6]),
        ];
        let (a, merges) = allocate_local(super::super::contract_net::allocate, &robots, &tasks, &p);
        assert_eq!(merges, 1);
        let coalitions = a.coalitions();
        for (j, ms) in &coalitions {
            assert!(ms.len() <= tasks[*j].robots_needed, "T{} over-full", j + 1);
        }
        let book: TaskBook = tasks.iter().map(|t| (t.id, t.clone())).collect();
        assert_eq!(
            a.paths,
            super::super::contract_net::allocate(&robots, &book, &p).paths
        );
    }
}
