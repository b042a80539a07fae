//! A scenario made ready to run: every section checked by its owner (the run's own sections by
//! swarm, the world core's limits and the robots' placement and the mission's section by the
//! world crate, then the behaviour's by the agent crate's registry), then
//! the behaviour's defaults written in, so the resolved scenario lists every value.

use swarm::scenario::{Check, ConfigError, Scenario};

/// Validates `sc` (errors name the key and `key_source(key)`, where its value came from) and
/// resolves the behaviour's defaults into it.
pub fn prepare(sc: &mut Scenario, key_source: &dyn Fn(&str) -> String) -> Result<(), ConfigError> {
    sc.validate(key_source)?;
    let c = Check { key_source };
    world::limits::validate(sc, &c)?;
    // The mission first: its range checks name the key the user wrote (`search.signal_m =
    // nan`) before the behaviour compares its own copies with them.
    world::mission::validate_with(sc, &c)?;
    agent::behaviours::validate_with(sc, &c)?;
    agent::behaviours::resolve_defaults(sc)
}

/// [`prepare`] with every key from one `source` (a file, a bench).
pub fn prepare_from(sc: &mut Scenario, source: &str) -> Result<(), ConfigError> {
    prepare(sc, &|_| source.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Values a hostile user writes for a float key: ordinary ones around the default, and the
    /// edges (0, negative, tiny, huge, NaN, inf).
    fn float(default: f64) -> impl Strategy<Value = f64> {
        prop_oneof![
            4 => (0.0..3.0f64).prop_map(move |k| default * k),
            1 => Just(0.0),
            1 => Just(-1.0),
            1 => Just(1e-9),
            1 => Just(1e9),
            1 => Just(f64::NAN),
            1 => Just(f64::INFINITY),
        ]
    }

    fn region() -> impl Strategy<Value = [f64; 4]> {
        prop_oneof![
            3 => (0.0..1000.0f64, 0.0..1000.0f64, 1.0..600.0f64, 1.0..600.0f64)
                .prop_map(|(x, y, w, h)| [x, y, x + w, y + h]),
            1 => prop::array::uniform4(-100.0..1100.0f64),
            1 => Just([0.0; 4]),
        ]
    }

    /// A scenario with a few keys of every kind set to drawn values.
    fn scenario() -> impl Strategy<Value = Scenario> {
        (
            (any::<bool>(), 1u32..12, any::<u64>()),
            (float(1000.0), float(1000.0), region(), float(2.0)),
            (float(10.0), float(100.0), float(1.0), float(300.0)),
            (0u32..40, region(), float(10.0), float(10.0), float(1.0)),
            (float(0.5), float(1.2), 0u64..8),
        )
            .prop_map(|(run, arena, robot, search, kernels)| {
                let (roam, robots, seed) = run;
                let mut sc = if roam {
                    Scenario::roam()
                } else {
                    Scenario::default()
                };
                sc.run.robots = robots;
                sc.run.seed = seed;
                sc.run.max_ticks = 2;
                (
                    sc.arena.width,
                    sc.arena.height,
                    sc.arena.start_region,
                    sc.arena.boundary_spacing,
                ) = arena;
                let (v_max, sensing, radius, comm) = robot;
                sc.robot.v_max = v_max;
                sc.robot.sensing_radius = sensing;
                // Bodies now and then.
                sc.robot.radius = if seed % 4 == 0 { radius } else { 0.0 };
                sc.radio.comm_radius = comm;
                let (targets, target_region, clearance, found, noise) = search;
                sc.search.targets = targets;
                sc.search.target_region = target_region;
                sc.search.target_clearance = clearance;
                sc.search.found_distance = found;
                sc.search.noise_sigma = noise;
                let (w, c3, declare) = kernels;
                sc.search.kernels = format!(
                    "declare_ticks = {declare}\n[tpepso]\nw = {w:?}\nc3 = {c3:?}\nv_max = {v_max:?}\n\
                     [virtual_force]\nv_max = {v_max:?}\n[arba]\nv_max = {v_max:?}\n\
                     [bsoa]\nv_max = {v_max:?}\n[svf]\nv_max = {v_max:?}\n"
                )
                .replace("NaN", "nan")
                .parse()
                .unwrap_or_default();
                sc
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

        /// Any scenario validation accepts can start: the world is created (placement,
        /// mission), and ticks apply with the real behaviours (in-process executor).
        #[test]
        fn any_accepted_scenario_starts_and_ticks(mut sc in scenario()) {
            if prepare_from(&mut sc, "proptest").is_ok() {
                let w = world::World::new(&sc);
                prop_assert!(w.is_ok(), "World::new: {:?}", w.err());
                let w = w.unwrap();
                prop_assert_eq!(w.mission.name(), world::mission::entry_for(&sc).unwrap().name);
                let summary = crate::inprocess::run(&sc, None, "proptest", 1, &mut |_| {});
                prop_assert!(summary.is_ok(), "run: {:?}", summary.err());
                prop_assert!(summary.unwrap().ticks >= 1);
            }
        }
    }

    #[test]
    fn signal_m_nan_is_named_as_itself_not_as_a_calibration_mismatch() {
        let mut sc = Scenario::default();
        sc.search.signal_m = f64::NAN;
        let e = prepare_from(&mut sc, "t.toml").unwrap_err();
        assert_eq!(e.key, "search.signal_m", "{e}");
    }
}
