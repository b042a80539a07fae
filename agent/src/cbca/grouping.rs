//! Grouping by local prior information (thesis sec. 4.2.2, spec 4.4, 10.3). Before allocating,
//! the robots split into temporary groups Ψ_s: the connected components of the communication
//! graph (robots within the communication radius, 1.5 km, are linked). A group knows the
//! targets its members detect (within 1.2 km) and share; each group runs CBCA on those. When
//! groups come into range they merge and share what they know.
//!
//! The thesis's Example 1 allocates T3, which no robot detects at t = 0 (spec 10.3), so its
//! groups must have had more prior information than their detections. [`PriorInfo`] names the
//! choices: detections only (the letter of sec. 4.2.2), detections plus every undetected target
//! given to the group whose nearest member is closest to it (our assumption that reproduces
//! the thesis's Example 1, where T3 goes to the second group), or everything (no grouping).

use std::collections::BTreeSet;

use serde::{Deserialize, Serialize};
use swarm::geometry::Vec2;

use super::model::{RobotId, Task, TaskId};

/// Which targets a temporary group knows before it allocates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PriorInfo {
    /// Only what its members detect.
    Detection,
    /// What its members detect, plus each target nobody detects, given to the group whose
    /// nearest member is closest to it (ties: the group with the smaller first member).
    DetectionPlusNearest,
    /// Every target (global prior information: CBCA without grouping).
    Global,
}

/// The communication graph: robot i's neighbours are the robots within `radius` (km).
pub fn comm_graph(positions: &[Vec2], radius: f64) -> Vec<Vec<RobotId>> {
    (0..positions.len())
        .map(|i| {
            (0..positions.len())
                .filter(|&j| j != i && (positions[i] - positions[j]).norm() <= radius)
                .collect()
        })
        .collect()
}

/// The temporary groups Ψ_s: connected components of the communication graph, each listed in
/// id order, groups ordered by their smallest member.
pub fn temporary_groups(positions: &[Vec2], radius: f64) -> Vec<Vec<RobotId>> {
    components(&comm_graph(positions, radius))
}

/// Connected components of a graph given as neighbour lists.
pub fn components(neighbours: &[Vec<RobotId>]) -> Vec<Vec<RobotId>> {
    let mut group_of = vec![usize::MAX; neighbours.len()];
    let mut groups = Vec::new();
    for start in 0..neighbours.len() {
        if group_of[start] != usize::MAX {
            continue;
        }
        let g = groups.len();
        let mut members = vec![start];
        group_of[start] = g;
        let mut k = 0;
        while k < members.len() {
            for &n in &neighbours[members[k]] {
                if group_of[n] == usize::MAX {
                    group_of[n] = g;
                    members.push(n);
                }
            }
            k += 1;
        }
        members.sort_unstable();
        groups.push(members);
    }
    groups
}

/// The targets within `radius` of some member.
pub fn detected(
    members: &[RobotId],
    positions: &[Vec2],
    tasks: &[Task],
    radius: f64,
) -> BTreeSet<TaskId> {
    tasks
        .iter()
        .filter(|t| {
            members
                .iter()
                .any(|&m| (positions[m] - t.pos()).norm() <= radius)
        })
        .map(|t| t.id)
        .collect()
}

/// What each group knows before allocating, under `prior`.
pub fn group_knowledge(
    groups: &[Vec<RobotId>],
    positions: &[Vec2],
    tasks: &[Task],
    detection_radius: f64,
    prior: PriorInfo,
) -> Vec<BTreeSet<TaskId>> {
    if prior == PriorInfo::Global {
        return groups
            .iter()
            .map(|_| tasks.iter().map(|t| t.id).collect())
            .collect();
    }
    let mut known: Vec<BTreeSet<TaskId>> = groups
        .iter()
        .map(|g| detected(g, positions, tasks, detection_radius))
        .collect();
    if prior == PriorInfo::DetectionPlusNearest && !groups.is_empty() {
        let seen: BTreeSet<TaskId> = known.iter().flatten().copied().collect();
        for t in tasks.iter().filter(|t| !seen.contains(&t.id)) {
            let dist = |g: &Vec<RobotId>| {
                g.iter()
                    .map(|&m| (positions[m] - t.pos()).norm())
                    .fold(f64::INFINITY, f64::min)
            };
            let mut best = 0;
            for (s, g) in groups.iter().enumerate() {
                if dist(g) < dist(&groups[best]) {
                    best = s;
                }
            }
            known[best].insert(t.id);
        }
    }
    known
}

/// What each ROBOT knows at the start under `prior`, before any message: its own detections;
/// with [`PriorInfo::DetectionPlusNearest`] also each target nobody detects for which it is the
/// nearest robot (so the nearest group learns it over the radio); with [`PriorInfo::Global`]
/// everything. Sharing inside a group is then the consensus messages' job.
pub fn robot_knowledge(
    positions: &[Vec2],
    tasks: &[Task],
    detection_radius: f64,
    prior: PriorInfo,
) -> Vec<BTreeSet<TaskId>> {
    let mut known: Vec<BTreeSet<TaskId>> = (0..positions.len())
        .map(|i| match prior {
            PriorInfo::Global => tasks.iter().map(|t| t.id).collect(),
            _ => detected(&[i], positions, tasks, detection_radius),
        })
        .collect();
    if prior == PriorInfo::DetectionPlusNearest && !positions.is_empty() {
        let seen: BTreeSet<TaskId> = known.iter().flatten().copied().collect();
        for t in tasks.iter().filter(|t| !seen.contains(&t.id)) {
            let mut best = 0;
            for i in 0..positions.len() {
                if (positions[i] - t.pos()).norm() < (positions[best] - t.pos()).norm() {
                    best = i;
                }
            }
            known[best].insert(t.id);
        }
    }
    known
}

/// A merge: a new group made of members of several old groups.
#[derive(Clone, Debug, PartialEq)]
pub struct Merge {
    pub members: Vec<RobotId>,
    /// Indices of the old groups it joins.
    pub from: Vec<usize>,
}

/// The merges between the old groups and the groups of the current positions: every current
/// component holding members of more than one old group.
pub fn merges(old: &[Vec<RobotId>], now: &[Vec<RobotId>]) -> Vec<Merge> {
    let n = old
        .iter()
        .flatten()
        .chain(now.iter().flatten())
        .max()
        .map_or(0, |m| m + 1);
    let mut old_of = vec![usize::MAX; n];
    for (s, g) in old.iter().enumerate() {
        for &m in g {
            old_of[m] = s;
        }
    }
    now.iter()
        .filter_map(|g| {
            let from: BTreeSet<usize> = g
                .iter()
                .map(|&m| old_of[m])
                .filter(|&s| s != usize::MAX)
                .collect();
            (from.len() > 1).then(|| Merge {
                members: g.clone(),
                from: from.into_iter().collect(),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cbca::scenario::tests::example;

    fn ids(g: &[Vec<RobotId>]) -> Vec<Vec<usize>> {
        g.iter()
            .map(|g| g.iter().map(|m| m + 1).collect())
            .collect()
    }

    #[test]
    fn example1_gives_two_groups_at_1_5_km() {
        let s = example(1);
        let pos: Vec<Vec2> = s.robots().unwrap().iter().map(|r| r.position).collect();
        let g = temporary_groups(&pos, 1.5);
        assert_eq!(
            ids(&g),
            vec![
                vec![1, 2, 3, 4, 5, 6, 10],
                vec![7, 8, 9, 11, 12, 13, 14, 15]
            ]
        );
        // Detections (1.2 km): group 1 sees T1 (R2 1.00 km, R3 0.72 km) and T2 (R5 1.02 km, R6
        // 0.68 km); group 2 sees T4 (R7 0.71 km); nobody sees T3 (> 3.4 km from everyone).
        let tasks = s.tasks().unwrap();
        let k = group_knowledge(&g, &pos, &tasks, 1.2, PriorInfo::Detection);
        assert_eq!(k, vec![[0, 1].into(), [3].into()]);
        // The nearest member to T3 (2.34, 6.96) is R7 (5.64, 7.82), 3.41 km, in group 2.
        let k = group_knowledge(&g, &pos, &tasks, 1.2, PriorInfo::DetectionPlusNearest);
        assert_eq!(k, vec![[0, 1].into(), [2, 3].into()]);
        assert_eq!(
            group_knowledge(&g, &pos, &tasks, 1.2, PriorInfo::Global)[0].len(),
            4
        );
        // Per robot: R3 (index 2) detects T1; R7 (index 6) detects T4 and, as the nearest
        // robot, is handed T3; R10 (index 9) detects nothing.
        let r = robot_knowledge(&pos, &tasks, 1.2, PriorInfo::DetectionPlusNearest);
        assert_eq!(r[2], [0].into());
        assert_eq!(r[6], [2, 3].into());
        assert!(r[9].is_empty());
    }

    #[test]
    fn example2_gives_six_components_at_1_5_km_and_two_at_2_km() {
        let s = example(2);
        let pos: Vec<Vec2> = s.robots().unwrap().iter().map(|r| r.position).collect();
        // spec 10.3: {1,2}, {3,15}, {4,5,6}, {7,8,11,13,14}, {9}, {10,12}.
        assert_eq!(
            ids(&temporary_groups(&pos, 1.5)),
            vec![
                vec![1, 2],
                vec![3, 15],
                vec![4, 5, 6],
                vec![7, 8, 11, 13, 14],
                vec![9],
                vec![10, 12]
            ]
        );
        assert_eq!(
            ids(&temporary_groups(&pos, 2.0)),
            vec![
                vec![1, 2, 3, 4, 5, 6, 15],
                vec![7, 8, 9, 10, 11, 12, 13, 14]
            ]
        );
    }

    #[test]
    fn groups_merge_when_they_come_into_range() {
        let mut pos = vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(5.0, 0.0),
            Vec2::new(9.0, 0.0),
        ];
        let old = temporary_groups(&pos, 1.5);
        assert_eq!(old, vec![vec![0, 1], vec![2], vec![3]]);
        pos[2] = Vec2::new(2.2, 0.0); // robot 2 comes within 1.5 km of robot 1
        let now = temporary_groups(&pos, 1.5);
        assert_eq!(
            merges(&old, &now),
            vec![Merge {
                members: vec![0, 1, 2],
                from: vec![0, 1]
            }]
        );
        assert!(merges(&old, &old).is_empty());
    }
}
