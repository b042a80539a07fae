//! Where the robots run (`[[hosts]]`, issue 41): robots listed under a host run on that host,
//! under its host proxy (`orchestrator host --join ENDPOINT --name NAME`); the others run on
//! the world's host. Where a robot runs changes no result, so the section is never written
//! into a resolved scenario (nor, through it, into a recording): a run across hosts records
//! the bytes of the same run on one host.

use crate::scenario::{Check, ConfigError, Scenario};
use serde::{Deserialize, Serialize};

/// The world host's Zenoh listen endpoint when neither `hosts_listen` nor `up --listen` sets
/// one: every address, Zenoh's usual port.
pub const DEFAULT_LISTEN: &str = "tcp/0.0.0.0:7447";

/// Longest host name (bytes): it is part of Zenoh key expressions and of error messages.
pub const MAX_HOST_NAME: usize = 32;

/// One remote host and its robots.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HostSpec {
    /// The name its proxy joins with (`orchestrator host --name`): letters, digits, `-`, `_`.
    pub name: String,
    /// Its robots: a range `"10..20"` (end excluded) or a list `[3, 4, 9]`.
    pub robots: RobotSet,
}

/// A host's robots, as written.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(untagged)]
pub enum RobotSet {
    Range(String),
    List(Vec<u32>),
}

impl RobotSet {
    /// The robots, or why not (a range that does not parse).
    pub fn ids(&self) -> Result<Vec<u32>, String> {
        match self {
            RobotSet::List(v) => Ok(v.clone()),
            RobotSet::Range(s) => {
                let bad = || {
                    format!(
                        "= {s:?} is not a range \"FROM..TO\" (TO excluded) nor a list of robots"
                    )
                };
                let (a, b) = s.split_once("..").ok_or_else(bad)?;
                let a: u32 = a.trim().parse().map_err(|_| bad())?;
                let b: u32 = b.trim().parse().map_err(|_| bad())?;
                if a >= b {
                    return Err(format!("= {s:?} is an empty range (FROM must be below TO)"));
                }
                Ok((a..b).collect())
            }
        }
    }
}

/// The host of each robot: `None` for the world's host, else the index in `hosts`. Only for a
/// validated scenario (robots in range, on one host each).
pub fn placement(sc: &Scenario) -> Vec<Option<usize>> {
    let mut at = vec![None; sc.run.robots as usize];
    for (h, spec) in sc.hosts.iter().enumerate() {
        for r in spec.robots.ids().unwrap_or_default() {
            if let Some(slot) = at.get_mut(r as usize) {
                *slot = Some(h);
            }
        }
    }
    at
}

/// Checks `[[hosts]]` and `hosts_listen`: names well-formed and distinct, every robot in
/// `0..run.robots` and on one host at most, and a lock-step run with the futex barrier (a
/// run across hosts is lock-step only: real-time mode would need the world's clock on every
/// host).
pub fn validate(sc: &Scenario, c: &Check) -> Result<(), ConfigError> {
    if let Some(l) = &sc.hosts_listen {
        check_endpoint(l).map_err(|m| c.err("hosts_listen", m))?;
    }
    if sc.hosts.is_empty() {
        return Ok(());
    }
    if sc.runtime.is_realtime() {
        return Err(c.err(
            "runtime.realtime_hz",
            "must be 0 in a run across hosts ([[hosts]]): runs across hosts are lock-step only"
                .into(),
        ));
    }
    if sc.runtime.barrier != crate::scenario::BarrierKind::Futex {
        return Err(c.err(
            "runtime.barrier",
            "must be \"futex\" in a run across hosts ([[hosts]])".into(),
        ));
    }
    if sc.runtime.acts != crate::scenario::ActsKind::PubSub {
        return Err(c.err(
            "runtime.acts",
            "must be \"pub-sub\" in a run across hosts ([[hosts]]): a remote robot's restart \
             over blackboards is not reliable yet"
                .into(),
        ));
    }
    let mut owner: Vec<Option<usize>> = vec![None; sc.run.robots as usize];
    for (h, spec) in sc.hosts.iter().enumerate() {
        let key = format!("hosts[{h}].name");
        let ok = !spec.name.is_empty()
            && spec.name.len() <= MAX_HOST_NAME
            && spec
                .name
                .bytes()
                .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_');
        if !ok {
            return Err(c.err(
                &key,
                format!(
                    "= {} is not a host name: allowed 1 to {MAX_HOST_NAME} letters, digits, `-` and `_`",
                    crate::scenario_shape::shown(&spec.name)
                ),
            ));
        }
        if let Some(o) = sc.hosts[..h].iter().position(|o| o.name == spec.name) {
            return Err(c.err(
                &key,
                format!(
                    "= {:?} is also the name of hosts[{o}]: host names must differ",
                    spec.name
                ),
            ));
        }
        let key = format!("hosts[{h}].robots");
        let ids = spec.robots.ids().map_err(|m| c.err(&key, m))?;
        if ids.is_empty() {
            return Err(c.err(&key, "is empty: a host runs one robot at least".into()));
        }
        for r in ids {
            let Some(slot) = owner.get_mut(r as usize) else {
                return Err(c.err(
                    &key,
                    format!(
                        "names robot {r}: allowed 0..{} (run.robots = {})",
                        sc.run.robots, sc.run.robots
                    ),
                ));
            };
            if let Some(o) = *slot {
                return Err(c.err(
                    &key,
                    format!(
                        "names robot {r}, which hosts[{o}] ({:?}) runs already",
                        sc.hosts[o].name
                    ),
                ));
            }
            *slot = Some(h);
        }
    }
    Ok(())
}

/// A Zenoh endpoint as this runtime uses them: `tcp/ADDRESS:PORT`.
pub fn check_endpoint(e: &str) -> Result<(), String> {
    let ok = e
        .strip_prefix("tcp/")
        .and_then(|a| a.rsplit_once(':'))
        .is_some_and(|(host, port)| !host.is_empty() && port.parse::<u16>().is_ok());
    if ok {
        Ok(())
    } else {
        Err(format!(
            "= {} is not an endpoint: allowed tcp/ADDRESS:PORT (e.g. tcp/10.7.0.1:7447)",
            crate::scenario_shape::shown(e)
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scenario `text`, read from a file (error sources name its lines), with 10 robots.
    fn parse(text: &str) -> Result<Scenario, ConfigError> {
        let path = std::env::temp_dir().join(format!("swarm-hosts-{}.toml", std::process::id()));
        std::fs::write(&path, text).unwrap();
        let name = path.display().to_string();
        let sc = Scenario::parse(text, &name).map(|mut sc| {
            sc.run.robots = 10;
            sc
        });
        let r = sc.and_then(|sc| sc.validate(&|_| name.clone()).map(|_| sc));
        let _ = std::fs::remove_file(&path);
        r.map_err(|mut e| {
            // The file's name varies with the process: only its line is compared.
            e.source = e.source.replace(&name, "h.toml");
            e
        })
    }

    #[test]
    fn hosts_are_read_and_placed() {
        let sc = parse(
            "hosts_listen = \"tcp/10.7.0.1:7447\"\n[[hosts]]\nname = \"a\"\nrobots = \"2..4\"\n\
             [[hosts]]\nname = \"b\"\nrobots = [9, 5]\n",
        )
        .unwrap();
        let p = placement(&sc);
        assert_eq!(p[2], Some(0));
        assert_eq!(p[3], Some(0));
        assert_eq!(p[9], Some(1));
        assert_eq!(p[0], None);
        // Never in a resolved scenario: a run across hosts records what one host records.
        assert!(!sc.to_toml().contains("hosts"));
    }

    #[test]
    fn bad_hosts_name_the_key_and_line() {
        let e = parse(
            "[[hosts]]\nname = \"a\"\nrobots = \"2..4\"\n[[hosts]]\nname = \"b\"\nrobots = [3]\n",
        )
        .unwrap_err();
        assert_eq!(e.key, "hosts[1].robots");
        assert_eq!(e.source, "h.toml:6");
        assert!(e.message.contains("robot 3"), "{e}");
        let e = parse("[[hosts]]\nname = \"a b\"\nrobots = [1]\n").unwrap_err();
        assert_eq!(e.key, "hosts[0].name");
        let e = parse("[[hosts]]\nname = \"a\"\nrobots = \"4..40\"\n").unwrap_err();
        assert!(e.message.contains("allowed 0..10"), "{e}");
        let e = parse("hosts_listen = \"udp/x\"\n").unwrap_err();
        assert_eq!(e.key, "hosts_listen");
        let e = parse("[runtime]\nrealtime_hz = 10.0\n[[hosts]]\nname = \"a\"\nrobots = [1]\n")
            .unwrap_err();
        assert_eq!(e.key, "runtime.realtime_hz");
    }
}
