//! The `[hunt]` section of a scenario file: the robots (`[[hunt.robots]]`, Table 3.2), the
//! evaders (`[[hunt.evaders]]`, Table 3.1) and the tunables (`[hunt.params]`). The section's
//! types live in `swarm::sections::hunt` (the world's mission reads them too); here they become
//! kernel types. `configs/hunt-example-3a.toml` is Example 3-A.

use crate::hunt::model::{Robot, Task};
use swarm::geometry::Vec2;
pub use swarm::sections::hunt::{
    AuctioneerSpec, EvaderSpec, HuntConfigError, HuntSection, RobotSpec,
};

/// The section's rows as kernel types.
pub trait HuntKernels {
    /// The robots, in the section's order (world robot k is `robots()[k]`).
    fn robots(&self) -> Vec<Robot>;
    /// The tasks (targets) present at time `t` minutes.
    fn tasks_at(&self, t: f64) -> Vec<Task>;
    /// Every task, whenever it appears.
    fn tasks(&self) -> Vec<Task>;
}

impl HuntKernels for HuntSection {
    fn robots(&self) -> Vec<Robot> {
        self.robots.iter().map(robot_of).collect()
    }

    fn tasks_at(&self, t: f64) -> Vec<Task> {
        self.evaders
            .iter()
            .filter(|e| e.appears_at <= t)
            .map(task_of)
            .collect()
    }

    fn tasks(&self) -> Vec<Task> {
        self.evaders.iter().map(task_of).collect()
    }
}

/// A `[[hunt.robots]]` row as a kernel robot.
pub fn robot_of(r: &RobotSpec) -> Robot {
    Robot {
        id: r.id,
        position: Vec2::new(r.position[0], r.position[1]),
        heading: r.heading,
        resources: r.resources,
        matching: r.matching.clone(),
        speed: r.speed,
        turn_rate: r.turn_rate,
        max_mileage: r.max_mileage.unwrap_or(f64::INFINITY),
        travelled: 0.0,
    }
}

/// A `[[hunt.evaders]]` row as a kernel task.
pub fn task_of(e: &EvaderSpec) -> Task {
    Task {
        id: e.id,
        position: Vec2::new(e.position[0], e.position[1]),
        resources: e.resources,
        required_robots: e.required_robots,
        reward_cap: e.reward_cap,
        speed: e.speed,
        min_robot_speed: e.min_robot_speed,
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) fn example_3a() -> HuntSection {
        let text = include_str!("../../../configs/hunt-example-3a.toml");
        HuntSection::from_scenario_toml(text).expect("configs/hunt-example-3a.toml parses")
    }

    #[test]
    fn example_3a_is_tables_3_1_and_3_2() {
        let h = example_3a();
        assert_eq!(h.robots.len(), 15);
        assert_eq!(h.evaders.len(), 5);
        // Table 3.1 row 1 and row 4.
        let t1 = &h.evaders[0];
        assert_eq!(
            (t1.id, t1.position, t1.required_robots, t1.reward_cap),
            (1, [1.94, 9.11], 3, 520.0)
        );
        assert_eq!(t1.resources, [10.0, 9.0, 14.0, 15.0, 18.0, 15.0]);
        let t4 = &h.evaders[3];
        assert_eq!(
            (t4.position, t4.required_robots, t4.reward_cap),
            ([7.21, 5.36], 5, 1350.0)
        );
        // T5: only z_5max = 1600 is printed (Table 3.3); it appears mid-run.
        assert_eq!(h.evaders[4].reward_cap, 1600.0);
        assert!(h.evaders[4].appears_at > 0.0);
        assert_eq!(h.tasks_at(0.0).len(), 4);
        // Table 3.2 rows 1, 10 and 14 (R14's trailing 7th resource dropped, spec 12 item 14).
        let r = h.robots();
        assert_eq!(r[0].position, Vec2::new(1.54, 6.88));
        assert_eq!(r[0].matching, vec![0.4, 0.1, 0.3, 0.1, 0.1]);
        assert_eq!(r[9].resources, [3.0, 4.0, 5.0, 4.0, 3.0, 2.0]);
        assert_eq!(r[13].resources, [2.0, 3.0, 7.0, 8.0, 5.0, 3.0]);
        // The g rows of R8, R9, R12, R13 sum to 0.8 as printed (spec 10.1): kept.
        for (i, row) in r.iter().enumerate() {
            let s: f64 = row.matching.iter().sum();
            let expect = if [8, 9, 12, 13].contains(&(i + 1)) {
                0.8
            } else {
                1.0
            };
            assert!((s - expect).abs() < 1e-9, "R{} g sums to {s}", i + 1);
        }
        // R10 fails T3's speed capability (sec. 3.3), every other robot meets it.
        let t3 = &h.tasks()[2];
        for robot in &r {
            assert_eq!(
                crate::hunt::model::speed_capable(robot.speed, t3),
                robot.id != 10,
                "R{}",
                robot.id
            );
        }
    }

    #[test]
    fn seven_resources_are_rejected() {
        let text = r#"
            [hunt]
            [[hunt.robots]]
            id = 14
            position = [5.89, 7.82]
            matching = [0.1, 0.1, 0.5, 0.2, 0.1]
            resources = [2, 3, 7, 8, 5, 3, 2]
            speed = 0.7
            turn_rate = 6.0
        "#;
        assert!(matches!(
            HuntSection::from_scenario_toml(text),
            Err(HuntConfigError::Parse(_))
        ));
    }

    #[test]
    fn duplicate_ids_and_bad_speeds_are_rejected() {
        let row = |id: u32, speed: f64| {
            format!(
                "[[hunt.robots]]\nid = {id}\nposition = [1, 1]\nmatching = [1.0]\nresources = [1,1,1,1,1,1]\nspeed = {speed}\nturn_rate = 6.0\n"
            )
        };
        let text = format!("[hunt]\n{}{}", row(1, 0.8), row(1, 0.8));
        assert!(matches!(
            HuntSection::from_scenario_toml(&text),
            Err(HuntConfigError::Invalid(e)) if e.key == "hunt.robots[1].id"
        ));
        let text = format!("[hunt]\n{}", row(2, 0.0));
        assert!(matches!(
            HuntSection::from_scenario_toml(&text),
            Err(HuntConfigError::Invalid(e)) if e.key == "hunt.robots[0].speed"
        ));
    }
}
