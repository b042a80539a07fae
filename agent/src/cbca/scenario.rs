//! The `[cbca]` section of a scenario file: parameters, target rows (Tables 4.1 / 4.3) and robot
//! rows (Tables 4.2 / 4.4), with the thesis's 1-based ids, turned into the model's types.

use serde::{Deserialize, Serialize};
use swarm::geometry::Vec2;

use super::model::{Resources, Robot, Task, TaskBook, RESOURCE_TYPES};
use super::params::CbcaParams;

/// One target row (Tables 4.1, 4.3).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskRow {
    /// The thesis's j (1-based, rows in order).
    pub id: usize,
    pub position: [f64; 2],
    /// V_aj.
    pub value: f64,
    /// E_j.
    pub resources: Vec<f64>,
    /// beta_j (default: params.default_beta).
    pub beta: Option<f64>,
    /// L_j.
    pub robots_needed: usize,
    /// Principle 4 hold time (default: params.hold_time).
    pub hold_time: Option<f64>,
}

/// One robot row (Tables 4.2, 4.4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotRow {
    /// The thesis's i (1-based, rows in order).
    pub id: usize,
    pub position: [f64; 2],
    /// gamma_i (default: params.default_gamma).
    pub gamma: Option<f64>,
    /// E_i'.
    pub resources: Vec<f64>,
    /// km per time unit (default: params.robot_speed).
    pub speed: Option<f64>,
    /// d^c_max (default: params.mileage_budget_km).
    pub mileage_budget_km: Option<f64>,
}

/// A `[cbca]` section.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CbcaScenario {
    pub params: CbcaParams,
    pub tasks: Vec<TaskRow>,
    pub robots: Vec<RobotRow>,
}

/// A file holding only a `[cbca]` section (the example data files).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CbcaFile {
    pub cbca: CbcaScenario,
}

#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    #[error("{what} row {index}: id {id}, expected {expected} (ids are 1-based and in order)")]
    BadId {
        what: &'static str,
        index: usize,
        id: usize,
        expected: usize,
    },
    #[error("{what} {id}: {len} resource entries, expected {RESOURCE_TYPES}")]
    ResourceCount {
        what: &'static str,
        id: usize,
        len: usize,
    },
    #[error("task {id}: L_j must be at least 1")]
    NoRobotsNeeded { id: usize },
    #[error("cannot parse the scenario: {0}")]
    Parse(#[from] toml::de::Error),
}

fn resources(what: &'static str, id: usize, v: &[f64]) -> Result<Resources, ScenarioError> {
    if v.len() != RESOURCE_TYPES {
        return Err(ScenarioError::ResourceCount {
            what,
            id,
            len: v.len(),
        });
    }
    let mut r = [0.0; RESOURCE_TYPES];
    r.copy_from_slice(v);
    Ok(r)
}

impl CbcaScenario {
    pub fn from_toml(text: &str) -> Result<Self, ScenarioError> {
        Ok(toml::from_str::<CbcaFile>(text)?.cbca)
    }

    /// The targets, as 0-based tasks.
    pub fn tasks(&self) -> Result<Vec<Task>, ScenarioError> {
        self.tasks
            .iter()
            .enumerate()
            .map(|(index, row)| {
                if row.id != index + 1 {
                    return Err(ScenarioError::BadId {
                        what: "task",
                        index,
                        id: row.id,
                        expected: index + 1,
                    });
                }
                if row.robots_needed == 0 {
                    return Err(ScenarioError::NoRobotsNeeded { id: row.id });
                }
                Ok(Task {
                    id: index,
                    position: row.position,
                    value: row.value,
                    required: resources("task", row.id, &row.resources)?,
                    beta: row.beta.unwrap_or(self.params.default_beta),
                    robots_needed: row.robots_needed,
                    hold_time: row.hold_time.unwrap_or(self.params.hold_time),
                })
            })
            .collect()
    }

    /// The targets as a book (every task known).
    pub fn task_book(&self) -> Result<TaskBook, ScenarioError> {
        Ok(self.tasks()?.into_iter().map(|t| (t.id, t)).collect())
    }

    /// The robots, as 0-based robots.
    pub fn robots(&self) -> Result<Vec<Robot>, ScenarioError> {
        self.robots
            .iter()
            .enumerate()
            .map(|(index, row)| {
                if row.id != index + 1 {
                    return Err(ScenarioError::BadId {
                        what: "robot",
                        index,
                        id: row.id,
                        expected: index + 1,
                    });
                }
                Ok(Robot {
                    id: index,
                    position: Vec2::new(row.position[0], row.position[1]),
                    gamma: row.gamma.unwrap_or(self.params.default_gamma),
                    resources: resources("robot", row.id, &row.resources)?,
                    speed: row.speed.unwrap_or(self.params.robot_speed),
                    max_tasks: self.params.max_tasks,
                    mileage_budget: row
                        .mileage_budget_km
                        .unwrap_or(self.params.mileage_budget_km),
                })
            })
            .collect()
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub fn example(n: u32) -> CbcaScenario {
        let path = format!(
            "{}/../configs/hunt-cbca-example{n}.toml",
            env!("CARGO_MANIFEST_DIR")
        );
        let text = std::fs::read_to_string(&path).expect("example file");
        CbcaScenario::from_toml(&text).expect("parses")
    }

    #[test]
    fn example1_holds_tables_4_1_and_4_2() {
        let s = example(1);
        let tasks = s.tasks().unwrap();
        let robots = s.robots().unwrap();
        assert_eq!(tasks.len(), 4);
        assert_eq!(robots.len(), 15);
        // Table 4.1 row 4: (5.75, 7.12), 230, {9,10,12,8,12,6}, 0.71, L = 4.
        assert_eq!(tasks[3].position, [5.75, 7.12]);
        assert_eq!(tasks[3].value, 230.0);
        assert_eq!(tasks[3].required, [9.0, 10.0, 12.0, 8.0, 12.0, 6.0]);
        assert_eq!(tasks[3].beta, 0.71);
        assert_eq!(tasks[3].robots_needed, 4);
        // Table 4.2 row 15, the 7th printed entry dropped: {2,3,7,8,5,3}.
        assert_eq!(robots[14].resources, [2.0, 3.0, 7.0, 8.0, 5.0, 3.0]);
        assert_eq!(robots[14].gamma, 0.8);
        assert_eq!(robots[9].position, Vec2::new(0.75, 1.68));
        assert_eq!(robots[0].max_tasks, 3);
        assert_eq!(s.params, CbcaParams::default());
        let total_needed: usize = tasks.iter().map(|t| t.robots_needed).sum();
        assert_eq!(total_needed, 13);
    }

    #[test]
    fn example2_holds_tables_4_3_and_4_4() {
        let s = example(2);
        let tasks = s.tasks().unwrap();
        let robots = s.robots().unwrap();
        assert_eq!(tasks.len(), 5);
        assert_eq!(robots.len(), 15);
        // Table 4.3 row 5: (1.45, 8.82), 600, {9,8,10,0,13,12}, 0.56, L = 3.
        assert_eq!(tasks[4].position, [1.45, 8.82]);
        assert_eq!(tasks[4].value, 600.0);
        assert_eq!(tasks[4].required[3], 0.0);
        assert_eq!(tasks[4].beta, 0.56);
        // Table 4.4 row 15: (2.01, 6.59), 0.8, {12,5,6,7,8,5}.
        assert_eq!(robots[14].position, Vec2::new(2.01, 6.59));
        assert_eq!(robots[14].resources, [12.0, 5.0, 6.0, 7.0, 8.0, 5.0]);
    }

    #[test]
    fn bad_rows_are_typed_errors() {
        let text = "[cbca]\n[[cbca.tasks]]\nid = 2\nposition = [0.0, 0.0]\nvalue = 1.0\n\
                    resources = [1.0, 1.0, 1.0, 1.0, 1.0, 1.0]\nrobots_needed = 1\n";
        let s = CbcaScenario::from_toml(text).unwrap();
        assert!(matches!(s.tasks(), Err(ScenarioError::BadId { id: 2, .. })));
        let text = "[cbca]\n[[cbca.robots]]\nid = 1\nposition = [0.0, 0.0]\n\
                    resources = [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 2.0]\n";
        let s = CbcaScenario::from_toml(text).unwrap();
        assert!(matches!(
            s.robots(),
            Err(ScenarioError::ResourceCount { len: 7, .. })
        ));
        assert!(matches!(
            CbcaScenario::from_toml("[cbca]\nbogus = 1\n"),
            Err(ScenarioError::Parse(_))
        ));
    }
}
