//! An experiment's variants: the conditions every run of it also runs under (radio loss,
//! robots killed, a scenario overlay, scenario keys set), as an experiment file lists them in
//! `[[variants]]`. Shared by every kind; names no paper.

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use swarm::scenario::{FaultPolicy, Scenario};

/// One condition of an experiment: what it changes in the scenario.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    pub name: String,
    /// radio.loss
    pub loss: Option<f64>,
    /// faults.kill_fraction: this share of the robots killed once each (SIGKILL under the
    /// processes executor).
    pub kill_fraction: Option<f64>,
    /// faults.kill_window
    pub kill_window: Option<[u64; 2]>,
    /// faults.on_fault: "drop" or "restart" (restart needs `--executor processes`).
    pub on_fault: Option<FaultPolicy>,
    /// A scenario file (relative to the experiment file) laid over the base scenario for this
    /// variant: its tables merge, its other values (arrays included: a new obstacle map)
    /// replace. Applied before `set`.
    pub overlay: Option<PathBuf>,
    /// Scenario keys this variant changes, as a TOML table laid over the base scenario
    /// (`[variants.set.search.kernels.virtual_force]` `l_r = 100.0`); applied after `overlay`.
    pub set: Option<toml::Table>,
}

/// Recursively lays `over` onto `base` (tables merge, everything else replaces), as a scenario
/// file is laid over the default.
fn merge_toml(base: &mut toml::Table, over: toml::Table) {
    for (k, v) in over {
        match (base.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge_toml(b, o),
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}

impl Variant {
    /// The base scenario with this variant's `overlay` and `set` laid over it (`dir`: the
    /// experiment file's folder).
    pub(crate) fn scenario(&self, base: &Scenario, dir: &Path) -> Result<Scenario, String> {
        if self.overlay.is_none() && self.set.is_none() {
            return Ok(base.clone());
        }
        let mut t: toml::Table = base.to_toml().parse().map_err(|e| format!("{e}"))?;
        if let Some(f) = &self.overlay {
            let path = dir.join(f);
            let text = std::fs::read_to_string(&path)
                .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
            let o: toml::Table = text
                .parse()
                .map_err(|e| format!("{}: {e}", path.display()))?;
            merge_toml(&mut t, o);
        }
        if let Some(o) = &self.set {
            merge_toml(&mut t, o.clone());
        }
        let source = format!("variant {:?}", self.name);
        Scenario::parse(&toml::to_string(&t).map_err(|e| e.to_string())?, &source)
            .map_err(|e| e.to_string())
    }

    pub(crate) fn apply(&self, sc: &mut Scenario) {
        if let Some(v) = self.loss {
            sc.radio.loss = v;
        }
        if let Some(v) = self.kill_fraction {
            sc.faults.kill_fraction = v;
        }
        if let Some(v) = self.kill_window {
            sc.faults.kill_window = v;
        }
        if let Some(v) = self.on_fault {
            sc.faults.on_fault = v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use search::SearchScenario;

    /// A variant's `set` lays its keys over the base scenario and leaves the others alone; an
    /// overlay file's array replaces the base's (a new obstacle map).
    #[test]
    fn a_variant_sets_scenario_keys_over_the_base() {
        let base = Scenario::default();
        let set: toml::Table =
            "[search.kernels.virtual_force]\nl_r = 100.0\n[arena]\nwalls_sensed = false\n"
                .parse()
                .unwrap();
        let v = Variant {
            name: "L_R 100".into(),
            set: Some(set),
            ..Variant::default()
        };
        let sc = v.scenario(&base, Path::new(".")).unwrap();
        assert_eq!(
            sc.search().kernels["virtual_force"]["l_r"].as_float(),
            Some(100.0)
        );
        assert!(!sc.arena.walls_sensed);
        assert_eq!(sc.arena.obstacles, base.arena.obstacles);
        assert_eq!(sc.run.seed, base.run.seed);
        let dir = std::env::temp_dir().join(format!("exp-overlay-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("map.toml"),
            "[[arena.obstacles]]\nname = \"one\"\npoints = [[10.0, 10.0], [40.0, 10.0], [40.0, 40.0]]\n",
        )
        .unwrap();
        let v = Variant {
            name: "map".into(),
            overlay: Some("map.toml".into()),
            ..Variant::default()
        };
        let sc = v.scenario(&base, &dir).unwrap();
        assert_eq!(sc.arena.obstacles.len(), 1);
        assert_eq!(sc.arena.obstacles[0].name, "one");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
