//! A live run is an ordinary iceoryx2 system: listed through iceoryx2's own API (what the
//! `iox2 service list` tool calls), its per-tick flows are iceoryx2 services with the names
//! `docs/protocol.md` gives, and every agent is attached to the Sense and air services.

use e2e::*;
use iceoryx2::prelude::*;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// How long the run is given to have every agent attached before the listing is judged.
const ATTACH_WITHIN: Duration = Duration::from_secs(60);

/// Every service of the run `run_id`, by name, with the number of nodes attached to it.
fn services_of(run_id: &str) -> BTreeMap<String, usize> {
    let prefix = swarm::transport::prefix_for(run_id);
    let config = swarm::transport::run_config(&prefix).unwrap();
    let mut found = BTreeMap::new();
    let _ = ipc::Service::list(&config, |s| {
        let nodes = s.dynamic_details.as_ref().map_or(0, |d| d.nodes.len());
        found.insert(s.static_details.name().to_string(), nodes);
        CallbackProgression::Continue
    });
    found
}

#[test]
fn a_live_runs_sense_air_and_act_services_are_listed_by_iceoryx2() {
    let _g = serial();
    swarm::transport::quiet_logs();
    const ROBOTS: usize = 5;
    let out = tmp_dir("iox2-list");
    let id = own_run_id("iox2-list");
    let child = spawn_up_as(
        &[
            "--scenario",
            roam(),
            "--robots",
            &ROBOTS.to_string(),
            "--max-ticks",
            "100000",
            // Paced, so the run is live while it is listed.
            "--tick-hz",
            "50",
        ],
        &out,
        Some(&id),
    );
    // Every agent attached (an agent opens the Sense service, its act service and then the
    // air, so wait for all of them): each shared service has the world and every agent as
    // nodes, each act service its agent and the world.
    let attached = |seen: &BTreeMap<String, usize>| {
        ["world/sense", "radio/air"]
            .iter()
            .all(|s| seen.get(*s).copied().unwrap_or(0) > ROBOTS)
            && (0..ROBOTS).all(|i| seen.get(&format!("robot/{i}/act")).copied().unwrap_or(0) >= 2)
    };
    let t = Instant::now();
    let mut seen = services_of(&id);
    while !attached(&seen) && t.elapsed() < ATTACH_WITHIN {
        std::thread::sleep(Duration::from_millis(50));
        seen = services_of(&id);
    }
    // SIGINT ends the run as Ctrl-C does (outputs written, shared memory removed).
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let o = child.wait_with_output().unwrap();
    let mut want = vec![
        "world/sense".to_string(),
        "radio/air".to_string(),
        "world/state".to_string(),
        "run/control".to_string(),
    ];
    want.extend((0..ROBOTS).map(|i| format!("robot/{i}/act")));
    for name in &want {
        assert!(seen.contains_key(name), "{name} not listed: {seen:?}");
    }
    for shared in ["world/sense", "radio/air"] {
        assert_eq!(
            seen[shared],
            1 + ROBOTS,
            "{shared}: the world and every agent: {seen:?}"
        );
    }
    for i in 0..ROBOTS {
        assert_eq!(
            seen[&format!("robot/{i}/act")],
            2,
            "its agent and the world"
        );
    }
    assert!(o.status.code().is_some(), "{}", stderr(&o));
    assert!(shm_of_run(&id).is_empty(), "{:?}", shm_of_run(&id));
}
