//! The world host's side of a run across hosts: waits for the declared hosts, then runs the
//! **gateway**, a thread of the orchestrator that is, to the world, the agents of every remote
//! robot (docs/protocol.md section 9). The world does not know: it sees attaches, acks and
//! Actions on the services and barrier words of those robots, as from local agents.

use super::link;
use super::wire::{self, Down, Up};
use super::HostsError;
use crate::hosts::gateway_tick::{Event, Gateway};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use swarm::barrier::TickBarrier;
use swarm::scenario::Scenario;
use zenoh::Session;

/// One remote host of the run.
pub struct Remote {
    pub name: String,
    pub robots: Vec<u32>,
}

/// The declared hosts, joined: their Zenoh session and, once started, the gateway thread.
pub struct Hosts {
    session: Session,
    remotes: Vec<Remote>,
    events: Option<Receiver<Event>>,
    /// Kept alive for the run: the world's liveliness token (a proxy whose world goes stops)
    /// and the subscribers feeding `events`.
    _keep: Vec<Box<dyn std::any::Any + Send>>,
    stop: Arc<AtomicBool>,
    failure: Arc<Mutex<Option<String>>>,
    thread: Option<JoinHandle<()>>,
}

impl Hosts {
    /// With `[[hosts]]` in the scenario: listens on the world host's endpoint and waits until
    /// every declared host's proxy has joined, within `runtime.startup_timeout_s`. None
    /// without `[[hosts]]`.
    pub fn wait(sc: &Scenario) -> Result<Option<Hosts>, HostsError> {
        if sc.hosts.is_empty() {
            return Ok(None);
        }
        let endpoint = sc
            .hosts_listen
            .clone()
            .unwrap_or_else(|| swarm::sections::hosts::DEFAULT_LISTEN.to_string());
        let session = link::listen(&endpoint)?;
        let remotes: Vec<Remote> = sc
            .hosts
            .iter()
            .map(|h| Remote {
                name: h.name.clone(),
                robots: h.robots.ids().unwrap_or_default(),
            })
            .collect();
        let (tx, rx) = mpsc::channel();
        let mut keep: Vec<Box<dyn std::any::Any + Send>> = Vec::new();
        let live_tx = tx.clone();
        keep.push(Box::new(link::watch(
            &session,
            wire::TOKENS,
            move |key, alive| {
                if let Some(h) = wire::host_of(&key) {
                    let h = h.to_string();
                    let _ = live_tx.send(if alive {
                        Event::Came(h)
                    } else {
                        Event::Gone(h)
                    });
                }
            },
        )?));
        keep.push(Box::new(link::subscribe(
            &session,
            wire::UPS,
            move |key, bytes| {
                if let Some(h) = wire::host_of(&key) {
                    let up = Up::decode(&bytes).unwrap_or_else(|e| Up::Failed(e.to_string()));
                    let _ = tx.send(Event::Up(h.to_string(), up));
                }
            },
        )?));
        keep.push(Box::new(link::token(&session, wire::WORLD_TOKEN)?));
        let timeout = Duration::from_secs(sc.runtime.startup_timeout_s);
        let until = Instant::now() + timeout;
        let mut joined: BTreeMap<String, bool> = BTreeMap::new();
        loop {
            let missing: Vec<&str> = remotes
                .iter()
                .map(|r| r.name.as_str())
                .filter(|n| !joined.get(*n).copied().unwrap_or(false))
                .collect();
            if missing.is_empty() {
                break;
            }
            if crate::signals::interrupted() {
                return Err(HostsError::Other(
                    crate::processes::INTERRUPTED_AT_START.into(),
                ));
            }
            let now = Instant::now();
            if now >= until {
                return Err(HostsError::Missing {
                    missing: missing.join(", "),
                    seconds: sc.runtime.startup_timeout_s,
                    endpoint,
                });
            }
            match rx.recv_timeout((until - now).min(WAIT_SLICE)) {
                Ok(Event::Came(h)) => {
                    joined.insert(h, true);
                }
                Ok(Event::Gone(h)) => {
                    joined.insert(h, false);
                }
                _ => {}
            }
        }
        Ok(Some(Hosts {
            session,
            remotes,
            events: Some(rx),
            _keep: keep,
            stop: Arc::default(),
            failure: Arc::default(),
            thread: None,
        }))
    }

    /// Starts the gateway for the run (its world is READY: the services exist) and sends
    /// each host the run's start. `barrier` is the orchestrator's own mapping of the run's
    /// barrier: the world's segment is sealed, so the gateway cannot map it writable itself.
    pub fn start(
        &mut self,
        sc: &Scenario,
        run_id: &str,
        prefix: &str,
        barrier: Arc<TickBarrier>,
    ) -> Result<(), HostsError> {
        let mut downs = Vec::new();
        for r in &self.remotes {
            let p = link::publisher(&self.session, wire::down_key(&r.name))?;
            link::put(
                &p,
                Down::Start {
                    run_id: run_id.to_string(),
                    scenario: sc.to_toml(),
                    robots: r.robots.clone(),
                }
                .encode(),
            )?;
            downs.push(p);
        }
        let events = self.events.take().expect("started once");
        let remotes: Vec<Remote> = self
            .remotes
            .iter()
            .map(|r| Remote {
                name: r.name.clone(),
                robots: r.robots.clone(),
            })
            .collect();
        let (sc, prefix) = (sc.clone(), prefix.to_string());
        let (stop, failure) = (self.stop.clone(), self.failure.clone());
        self.thread = Some(std::thread::spawn(move || {
            let result = Gateway::open(&sc, &prefix, barrier, remotes, downs)
                .and_then(|mut g| g.run(&events, &stop));
            if let Err(e) = result {
                *failure.lock().expect("not poisoned") = Some(e.to_string());
            }
        }));
        Ok(())
    }

    /// Why the hosts' part of the run failed, if it did (a host could not run its robots).
    pub fn failure(&self) -> Option<String> {
        self.failure.lock().expect("not poisoned").clone()
    }

    /// Ends the gateway (the run is over): each host gets the run's end.
    pub fn finish(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for Hosts {
    fn drop(&mut self) {
        self.finish();
    }
}

/// How often the wait for the hosts looks at an interrupt.
const WAIT_SLICE: Duration = Duration::from_millis(50);
