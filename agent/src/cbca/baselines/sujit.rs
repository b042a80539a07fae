//! Polynomial-time coalition formation with limited communication ranges (Sujit, Manathara,
//! Ghose & de Sousa 2014, the thesis's Ref. 70), as its idea is commonly described: the robot
//! that finds a target leads; it recruits, among the robots it can reach, the ones that arrive
//! soonest, until the coalition has what the target needs; sorting by arrival time keeps it
//! polynomial (O(n log n) a target).
//!
//! Assumptions (none of this is in the thesis or the spec):
//! - the leader of a target is the robot nearest to it (it would detect it first);
//! - it reaches only the robots of its communication component (radius params.comm_radius_km,
//!   multi-hop relays), the "limited communication range";
//! - candidates are those that can append the target to their path (sec. 4.1's constraints),
//!   sorted by their arrival time (eta), ties by id;
//! - it takes candidates in that order, skipping one that adds nothing to the residual need,
//!   until L_j members (the thesis's cardinality, 4.3); with fewer than L_j such candidates no
//!   coalition forms (the target is shelved); a full coalition that still leaves need uncovered
//!   forms anyway (the method stops at the size the task demands);
//! - targets are handled in id order, one after the other;
//! - messages: the leader's request to, and a reply from, every robot of its component, and an
//!   award to every member.

use swarm::geometry::Vec2;

use super::super::grouping::temporary_groups;
use super::super::model::{Robot, TaskBook};
use super::super::params::CbcaParams;
use super::{append_contribution, eta, recruit, Allocation};

pub fn allocate(robots: &[Robot], book: &TaskBook, params: &CbcaParams) -> Allocation {
    let mut alloc = Allocation::empty(robots.len());
    let positions: Vec<Vec2> = robots.iter().map(|r| r.position).collect();
    let groups = temporary_groups(&positions, params.comm_radius_km);
    for (&j, task) in book {
        let Some(leader) = robots.iter().min_by(|a, b| {
            let da = (a.position - task.pos()).norm();
            let db = (b.position - task.pos()).norm();
            da.total_cmp(&db).then(a.id.cmp(&b.id))
        }) else {
            continue;
        };
        let group = groups
            .iter()
            .find(|g| g.contains(&leader.id))
            .expect("every robot is in a group");
        alloc.messages += 2 * (group.len() as u64 - 1);
        let mut candidates: Vec<(f64, usize)> = group
            .iter()
            .filter(|&&i| {
                append_contribution(&robots[i], &alloc.paths[i], j, book, params).is_some()
            })
            .map(|&i| (eta(&robots[i], &alloc.paths[i], j, book), i))
            .collect();
        candidates.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        recruit(
            &mut alloc,
            robots,
            book,
            params,
            j,
            candidates.into_iter().map(|(_, i)| i),
        );
    }
    alloc
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cbca::model::tests::{robot, task};

    #[test]
    fn the_soonest_reachable_robots_join() {
        // T1 at (0, 0), L 2. R1 (0.5, 0) leads; R2 (1.5, 0) and R3 (2.5, 0) are in its
        // component (1 km apart); R4 (-1.2, 0) is nearer to T1 than R2 (1.2 < 1.5 km) but
        // 1.7 km from R1: another component, unreachable. Coalition {R1, R2}.
        let book: TaskBook = [(0, task(0, [0.0, 0.0], [2.0; 6], 2))]
            .into_iter()
            .collect();
        let robots = vec![
            robot(0, [0.5, 0.0], [1.0; 6]),
            robot(1, [1.5, 0.0], [1.0; 6]),
            robot(2, [2.5, 0.0], [1.0; 6]),
            robot(3, [-1.2, 0.0], [1.0; 6]),
        ];
        let a = allocate(&robots, &book, &CbcaParams::default());
        assert_eq!(a.paths, vec![vec![0], vec![0], vec![], vec![]]);
        // Requests and replies to 2 others, awards to 2.
        assert_eq!(a.messages, 6);
    }
}
