//! `[[agents]]`: robots whose agent is a program of the user's (issue 38), not the built-in
//! `agent` binary.
//!
//! ```toml
//! [[agents]]
//! robots = "10..20"              # half-open range (10 to 19); "10..=19" or [10, 12, 15] too
//! command = ["target/release/rust-boids", "--verbose"]  # program and arguments, no shell
//! cwd = "."                      # optional; default: the scenario file's folder
//! attach_timeout_s = 30          # optional: start-to-attach limit of one agent (DEFAULT_ATTACH_TIMEOUT_S)
//! [agents.params]                # optional: the program's own table (`Agent::params`)
//! cohesion = 0.01
//! ```
//!
//! A relative `cwd`, and a relative program path holding a `/` (`./boids`,
//! `target/release/boids`), resolve against the scenario file's folder; a bare program name
//! (`python3`) is looked up on PATH as a shell would. Robots no entry lists run the built-in
//! `run.behaviour`.

use crate::scenario::{Check, ConfigError};
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::{Deserialize, Serialize, Serializer};
use std::fmt;
use std::path::Path;

/// Most `[[agents]]` entries a scenario may hold: one a robot at most (MAX_ROBOTS).
pub const MAX_AGENT_ENTRIES: usize = crate::scenario::MAX_ROBOTS as usize;

/// How long an agent program may take to attach to the run (`attach_timeout_s`) unless its
/// entry says otherwise. [chosen] A Rust agent attaches in milliseconds and a Python one
/// (interpreter, NumPy import) in well under a second; 30 s leaves room for 50 of them
/// starting at once on 2 loaded cores, and is far below runtime.startup_timeout_s (120 s).
pub const DEFAULT_ATTACH_TIMEOUT_S: f64 = 30.0;
/// Largest `attach_timeout_s` (an hour: longer than any start-up).
pub const MAX_ATTACH_TIMEOUT_S: f64 = 3600.0;

/// One `[[agents]]` entry.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AgentEntry {
    /// The robots this program runs.
    pub robots: RobotSet,
    /// The program and its arguments (no shell: each string is one argument). The orchestrator
    /// appends the agent arguments (`--robot I --prefix P --scenario FILE --run-id R`).
    pub command: Vec<String>,
    /// The program's working directory (default: the scenario file's folder).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cwd: Option<String>,
    /// How long one agent of this program may take from its start to attaching to the run
    /// before the orchestrator kills it and fails the run naming the robot and the command
    /// (default [`DEFAULT_ATTACH_TIMEOUT_S`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub attach_timeout_s: Option<f64>,
    /// The program's own parameters, read with `swarm::agent::Agent::params`.
    #[serde(default, skip_serializing_if = "toml::Table::is_empty")]
    pub params: toml::Table,
    /// Written by the orchestrator into the resolved scenario: the file this entry came from,
    /// so that errors about its `params` name that file's lines (not the run folder's copy).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
}

/// Which robots an entry runs: a range written as a string (`"10..20"` half-open, `"10..=19"`
/// inclusive) or a list of ids (`[1, 4, 7]`).
#[derive(Clone, Debug, PartialEq)]
pub enum RobotSet {
    /// `start..end` (end excluded).
    Range {
        start: u32,
        end: u32,
    },
    List(Vec<u32>),
}

impl RobotSet {
    /// The robot ids, in the order written.
    pub fn ids(&self) -> Vec<u32> {
        match self {
            RobotSet::Range { start, end } => (*start..*end).collect(),
            RobotSet::List(l) => l.clone(),
        }
    }

    pub fn contains(&self, robot: u32) -> bool {
        match self {
            RobotSet::Range { start, end } => (*start..*end).contains(&robot),
            RobotSet::List(l) => l.contains(&robot),
        }
    }
}

/// What a robot set may be written as (in errors).
const ROBOTS_ALLOWED: &str =
    "a range \"A..B\" (B excluded) or \"A..=B\", or a list of robot ids [1, 4, 7]";

/// Parses `"10..20"` / `"10..=19"`.
fn parse_range(s: &str) -> Result<RobotSet, String> {
    let bad = || {
        format!(
            "= {} is not a robot range: allowed {ROBOTS_ALLOWED}",
            crate::scenario_shape::shown(s)
        )
    };
    let (a, b, inclusive) = if let Some((a, b)) = s.split_once("..=") {
        (a, b, true)
    } else if let Some((a, b)) = s.split_once("..") {
        (a, b, false)
    } else {
        return Err(bad());
    };
    let start: u32 = a.trim().parse().map_err(|_| bad())?;
    let end: u32 = b.trim().parse().map_err(|_| bad())?;
    let end = if inclusive {
        end.checked_add(1).ok_or_else(bad)?
    } else {
        end
    };
    if start >= end {
        return Err(format!(
            "= {} is an empty range: allowed {ROBOTS_ALLOWED} with A below B",
            crate::scenario_shape::shown(s)
        ));
    }
    Ok(RobotSet::Range { start, end })
}

impl Serialize for RobotSet {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            RobotSet::Range { start, end } => s.serialize_str(&format!("{start}..{end}")),
            RobotSet::List(l) => l.serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for RobotSet {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RobotSet;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(ROBOTS_ALLOWED)
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<RobotSet, E> {
                parse_range(s).map_err(E::custom)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<RobotSet, A::Error> {
                let mut out = Vec::new();
                while let Some(id) = seq.next_element::<u32>()? {
                    out.push(id);
                }
                Ok(RobotSet::List(out))
            }
        }
        d.deserialize_any(V)
    }
}

/// Checks the entries against a run of `robots` robots: each robot in range, listed by one
/// entry at most, each command non-empty. Errors name `agents[i].robots` / `.command`.
pub fn validate(entries: &[AgentEntry], robots: u32, c: &Check) -> Result<(), ConfigError> {
    if entries.len() > MAX_AGENT_ENTRIES {
        return Err(c.err(
            "agents",
            format!(
                "has {} entries: at most {MAX_AGENT_ENTRIES} (MAX_AGENT_ENTRIES, one a robot)",
                entries.len()
            ),
        ));
    }
    let mut owner: Vec<Option<usize>> = vec![None; robots as usize];
    for (i, e) in entries.iter().enumerate() {
        let key = format!("agents[{i}].robots");
        let ids = e.robots.ids();
        if ids.is_empty() {
            return Err(c.err(&key, format!("is empty: allowed {ROBOTS_ALLOWED}")));
        }
        for id in ids {
            let Some(slot) = owner.get_mut(id as usize) else {
                return Err(c.err(
                    &key,
                    format!(
                        "names robot {id}, but the run has robots 0..={} (run.robots = {robots})",
                        robots - 1
                    ),
                ));
            };
            if let Some(j) = *slot {
                let msg = if j == i {
                    format!("names robot {id} twice")
                } else {
                    format!(
                        "names robot {id}, which agents[{j}] runs already: a robot has one \
                         program"
                    )
                };
                return Err(c.err(&key, msg));
            }
            *slot = Some(i);
        }
        let key = format!("agents[{i}].command");
        match e.command.first() {
            None => {
                return Err(c.err(
                    &key,
                    "is empty: allowed a program and its arguments, e.g. \
                     [\"target/release/my-agent\"] or [\"python3\", \"boids.py\"]"
                        .into(),
                ))
            }
            Some(p) if p.trim().is_empty() => {
                return Err(c.err(
                    &format!("{key}[0]"),
                    "is an empty program name: allowed a program path or a name on PATH".into(),
                ))
            }
            Some(_) => {}
        }
        if let Some(t) = e.attach_timeout_s {
            c.range_f(
                &format!("agents[{i}].attach_timeout_s"),
                t,
                0.0,
                MAX_ATTACH_TIMEOUT_S,
                true,
            )?;
        }
        if let Some(cwd) = &e.cwd {
            if cwd.is_empty() {
                return Err(c.err(
                    &format!("agents[{i}].cwd"),
                    "is empty: allowed a folder (relative ones to the scenario file's folder)"
                        .into(),
                ));
            }
        }
    }
    Ok(())
}

impl AgentEntry {
    /// This entry's attach timeout.
    pub fn attach_timeout(&self) -> std::time::Duration {
        std::time::Duration::from_secs_f64(
            self.attach_timeout_s.unwrap_or(DEFAULT_ATTACH_TIMEOUT_S),
        )
    }
}

/// The index of the entry that runs `robot`, if any.
pub fn entry_of(entries: &[AgentEntry], robot: u32) -> Option<usize> {
    entries.iter().position(|e| e.robots.contains(robot))
}

/// Makes every entry's program path (when relative and holding a `/`) and `cwd` absolute,
/// against `dir` (the scenario file's folder), sets a missing `cwd` to `dir`, and records
/// `source` (the scenario file) in each entry that has none yet. Idempotent: the resolved
/// scenario of a run folder, read back by the agents, keeps the user's file as `source`.
pub fn resolve_paths(entries: &mut [AgentEntry], dir: &Path, source: &str) {
    let abs = |p: &str| -> String {
        let path = Path::new(p);
        if path.is_absolute() {
            p.to_string()
        } else {
            dir.join(path).display().to_string()
        }
    };
    for e in entries {
        if let Some(p) = e.command.first_mut() {
            if p.contains('/') {
                *p = abs(p);
            }
        }
        e.cwd = Some(match &e.cwd {
            Some(c) => abs(c),
            None => dir.display().to_string(),
        });
        if e.source.is_none() {
            e.source = Some(source.to_string());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(text: &str) -> Result<Vec<AgentEntry>, String> {
        #[derive(Deserialize)]
        struct T {
            agents: Vec<AgentEntry>,
        }
        toml::from_str::<T>(text)
            .map(|t| t.agents)
            .map_err(|e| e.to_string())
    }

    #[test]
    fn ranges_and_lists_parse_and_write_back() {
        let e = entries(
            "[[agents]]\nrobots = \"2..5\"\ncommand = [\"a\"]\n\
             [[agents]]\nrobots = \"5..=6\"\ncommand = [\"b\"]\n\
             [[agents]]\nrobots = [9, 7]\ncommand = [\"c\"]\n",
        )
        .unwrap();
        assert_eq!(e[0].robots.ids(), vec![2, 3, 4]);
        assert_eq!(e[1].robots.ids(), vec![5, 6]);
        assert_eq!(e[2].robots.ids(), vec![9, 7]);
        assert_eq!(entry_of(&e, 6), Some(1));
        assert_eq!(entry_of(&e, 8), None);
        let back = toml::to_string(&e[1]).unwrap();
        assert!(back.contains("robots = \"5..7\""), "{back}");
        for bad in ["\"5\"", "\"a..b\"", "\"5..5\"", "7"] {
            let r = entries(&format!("[[agents]]\nrobots = {bad}\ncommand = [\"a\"]\n"));
            assert!(r.unwrap_err().contains("A..B"), "{bad}");
        }
    }

    #[test]
    fn overlap_range_and_empty_command_are_named() {
        let c = Check {
            key_source: &|_| "t.toml".to_string(),
        };
        let e = entries(
            "[[agents]]\nrobots = \"0..3\"\ncommand = [\"a\"]\n\
             [[agents]]\nrobots = [5, 2]\ncommand = [\"b\"]\n",
        )
        .unwrap();
        let err = validate(&e, 10, &c).unwrap_err();
        assert_eq!(err.key, "agents[1].robots");
        assert!(err.message.contains("robot 2") && err.message.contains("agents[0]"));
        let err = validate(&e[..1], 2, &c).unwrap_err();
        assert!(err.message.contains("robot 2") && err.message.contains("0..=1"));
        let e = entries("[[agents]]\nrobots = [1]\ncommand = []\n").unwrap();
        assert_eq!(validate(&e, 2, &c).unwrap_err().key, "agents[0].command");
    }

    #[test]
    fn relative_paths_resolve_against_the_scenario_folder() {
        let mut e = entries(
            "[[agents]]\nrobots = [1]\ncommand = [\"bin/a\", \"x/y\"]\n\
             [[agents]]\nrobots = [2]\ncommand = [\"python3\", \"b.py\"]\ncwd = \"sub\"\n",
        )
        .unwrap();
        resolve_paths(&mut e, Path::new("/s"), "/s/t.toml");
        assert_eq!(e[0].command, vec!["/s/bin/a", "x/y"]);
        assert_eq!(e[0].cwd.as_deref(), Some("/s"));
        assert_eq!(e[1].command[0], "python3");
        assert_eq!(e[1].cwd.as_deref(), Some("/s/sub"));
        assert_eq!(e[1].source.as_deref(), Some("/s/t.toml"));
    }
}
