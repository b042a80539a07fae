//! Behaviours, chosen by the scenario's `run.behaviour`, and their registry.
//!
//! A behaviour is a folder or file here with a `NAME`, a `validate` of its scenario section, a
//! `resolve` that writes its defaults into the scenario (a no-op for most) and a `dispatch`
//! that calls a [`BehaviourVisitor`] with its constructor; adding one is adding its file and
//! its name in `registry!` below (which also declares its module).

use swarm::scenario::{Check, ConfigError, Scenario};

pub use swarm::plugin::BehaviourVisitor;

/// The registry: one line per behaviour module. Generates the list of names, the plug-in
/// [`Builtin`] (what the composed binaries know of each behaviour) and `validate` /
/// `resolve_defaults` / `dispatch` by name.
macro_rules! registry {
    ($($m:ident),* $(,)?) => {
        $(pub mod $m;)*

        /// Every behaviour an agent can run.
        pub const BEHAVIOURS: &[&str] = &[$($m::NAME),*];

        /// The behaviours of this crate as one plug-in (swarm::plugin).
        pub struct Builtin;

        impl swarm::plugin::Plugin for Builtin {
            /// The sections of the papers still in the core (swarm::sections), in the order
            /// a resolved scenario lists them.
            fn sections() -> Vec<swarm::plugin::SectionEntry> {
                use swarm::plugin::SectionEntry;
                use swarm::sections::{cbca, formation, hunt};
                vec![
                    SectionEntry::of::<formation::FormationSection>(),
                    SectionEntry::of::<hunt::HuntSection>(),
                    SectionEntry::of::<cbca::CbcaSection>(),
                ]
            }
            fn behaviours() -> Vec<swarm::plugin::BehaviourInfo> {
                vec![$(swarm::plugin::BehaviourInfo {
                    name: $m::NAME,
                    sections: $m::SECTIONS,
                    validate: $m::validate,
                    resolve: $m::resolve,
                }),*]
            }
            fn dispatch<V: BehaviourVisitor>(sc: &Scenario, v: V) -> Result<V::Out, V> {
                $(if sc.run.behaviour == $m::NAME {
                    return Ok($m::dispatch(sc, v));
                })*
                Err(v)
            }
        }

        /// The papers' missions are still the world crate's own (world::mission::MISSIONS).
        impl world::mission::Missions for Builtin {}

        /// Checks that `run.behaviour` names a behaviour and that its section is valid.
        pub fn validate_with(sc: &Scenario, c: &Check) -> Result<(), ConfigError> {
            $(if sc.run.behaviour == $m::NAME {
                return $m::validate(sc, c);
            })*
            Err(c.err(
                "run.behaviour",
                format!("= {:?} is unknown: allowed {:?}", sc.run.behaviour, BEHAVIOURS),
            ))
        }

        /// The scenario sections behaviour `name` reads (none for an unknown one).
        pub fn sections(name: &str) -> &'static [&'static str] {
            $(if name == $m::NAME {
                return $m::SECTIONS;
            })*
            &[]
        }

        /// Writes every parameter of the behaviour into the scenario, defaults included, so
        /// the run's resolved scenario.toml lists each value the algorithms use.
        pub fn resolve_defaults(sc: &mut Scenario) -> Result<(), ConfigError> {
            $(if sc.run.behaviour == $m::NAME {
                return $m::resolve(sc);
            })*
            Ok(())
        }

        /// Calls `v` with the constructor of the scenario's behaviour (validated beforehand).
        pub fn dispatch<V: BehaviourVisitor>(sc: &Scenario, v: V) -> V::Out {
            $(if sc.run.behaviour == $m::NAME {
                return $m::dispatch(sc, v);
            })*
            panic!("unknown behaviour {:?} (the scenario was not validated)", sc.run.behaviour)
        }
    };
}

registry!(roam, faulty, formation, hunt, cbca, keeper);

/// For behaviours whose commands are velocities (vx, vy): refuses unicycle kinematics.
pub fn require_holonomic(sc: &Scenario, c: &Check, behaviour: &str) -> Result<(), ConfigError> {
    if sc.robot.kinematics.is_holonomic() {
        Ok(())
    } else {
        Err(c.err(
            "robot.kinematics",
            format!("= {:?}: the {behaviour} behaviour commands velocities (vx, vy) and needs model = \"holonomic\"", sc.robot.kinematics),
        ))
    }
}

/// [`validate_with`], errors naming the scenario file (`source`) as where every key came from.
pub fn validate(sc: &Scenario, source: &str) -> Result<(), ConfigError> {
    validate_with(
        sc,
        &Check {
            key_source: &|_| source.to_string(),
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_behaviour_is_named_with_the_allowed_ones() {
        let mut sc = Scenario::default();
        sc.run.behaviour = "dance".into();
        let e = validate(&sc, "t.toml").unwrap_err();
        assert_eq!(e.key, "run.behaviour");
        assert!(
            e.to_string().contains("roam") && e.to_string().contains("formation"),
            "{e}"
        );
        for name in BEHAVIOURS {
            let mut sc = Scenario::default();
            if *name == cbca::NAME {
                // CBCA needs its rows (one a robot): its runnable scenario.
                let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../configs/hunt-cbca.toml");
                sc = Scenario::load(std::path::Path::new(path)).unwrap();
            }
            sc.run.behaviour = name.to_string();
            validate(&sc, "t.toml").unwrap();
        }
    }
}
