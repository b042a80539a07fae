//! The exit code of a run that ended, from its summary.json (README, "Exit codes").

use crate::{exit, signals};

/// Whether the run's mission is accomplished: search: every target found; hunt: every
/// evader captured; formation: formed; a mission with no goal (roam): a robot is alive at
/// the end.
pub fn mission_complete(v: &serde_json::Value) -> bool {
    let m = &v["mission"];
    let all = |done: &str, of: &str, s: &serde_json::Value| matches!((s[done].as_u64(), s[of].as_u64()), (Some(d), Some(n)) if d >= n);
    if m["search"].is_object() {
        all("found", "targets", &m["search"])
    } else if m["hunt"].is_object() {
        all("captured", "evaders", &m["hunt"])
    } else if m["formation"].is_object() {
        m["formation"]["formed"].as_bool() == Some(true)
    } else {
        v["alive_at_end"].as_u64().unwrap_or(0) > 0
    }
}

/// The exit code of a run whose summary is `v`: interrupted (128 + the signal), complete,
/// or mission not complete.
pub fn exit_code(v: &serde_json::Value) -> i32 {
    if v["end"].as_str() == Some("interrupted") {
        signals::exit_code()
    } else if mission_complete(v) {
        exit::COMPLETE
    } else {
        exit::MISSION_NOT_COMPLETE
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn each_mission_judged_by_its_own_goal() {
        let search = |found| json!({"end": "completed", "mission": {"search": {"found": found, "targets": 3}}});
        assert_eq!(exit_code(&search(3)), exit::COMPLETE);
        assert_eq!(exit_code(&search(2)), exit::MISSION_NOT_COMPLETE);
        let hunt = json!({"end": "completed", "mission": {"hunt": {"captured": 1, "evaders": 2}}});
        assert_eq!(exit_code(&hunt), exit::MISSION_NOT_COMPLETE);
        let formed = json!({"end": "completed", "mission": {"formation": {"formed": true}}});
        assert_eq!(exit_code(&formed), exit::COMPLETE);
        let roam =
            |end, alive| json!({"end": end, "alive_at_end": alive, "mission": {"coverage": 0.5}});
        assert_eq!(exit_code(&roam("completed", 2)), exit::COMPLETE);
        assert_eq!(
            exit_code(&roam("all robots dead", 0)),
            exit::MISSION_NOT_COMPLETE
        );
        assert_eq!(exit_code(&roam("completed", 0)), exit::MISSION_NOT_COMPLETE);
    }
}
