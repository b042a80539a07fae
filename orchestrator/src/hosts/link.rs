//! The Zenoh link between the world's host and the remote hosts: TCP to the given endpoints
//! only (no multicast or gossip scouting, so a run never reaches past the addresses it is
//! given), reliable (TCP, Zenoh's default reliability), blocking congestion control (a full
//! queue waits rather than drops a tick's message) and express messages (sent at once, never
//! held back to be batched with the next).

use super::HostsError;
use std::time::{Duration, Instant};
use zenoh::qos::CongestionControl;
use zenoh::{Session, Wait};

/// How long a proxy waits between attempts to reach the world's host.
const JOIN_RETRY: Duration = Duration::from_millis(200);

fn config(mode: &str, listen: &[&str], connect: &[&str]) -> Result<zenoh::Config, HostsError> {
    let mut c = zenoh::Config::default();
    let list = |v: &[&str]| {
        let quoted: Vec<String> = v.iter().map(|e| format!("{e:?}")).collect();
        format!("[{}]", quoted.join(","))
    };
    for (key, value) in [
        ("mode", format!("{mode:?}")),
        ("listen/endpoints", list(listen)),
        ("connect/endpoints", list(connect)),
        ("scouting/multicast/enabled", "false".to_string()),
        ("scouting/gossip/enabled", "false".to_string()),
    ] {
        c.insert_json5(key, &value).map_err(|e| HostsError::Zenoh {
            what: format!("configure {key}"),
            message: e.to_string(),
        })?;
    }
    Ok(c)
}

/// The world's host: a Zenoh peer listening on `endpoint`.
pub fn listen(endpoint: &str) -> Result<Session, HostsError> {
    let c = config("peer", &[endpoint], &[])?;
    zenoh::open(c).wait().map_err(|e| HostsError::Zenoh {
        what: format!("listen on {endpoint}"),
        message: e.to_string(),
    })
}

/// A remote host: a Zenoh client of the world's host at `endpoint`, tried again every
/// [`JOIN_RETRY`] until `patience` has passed (the proxy may start before `up`).
pub fn join(endpoint: &str, patience: Duration) -> Result<Session, HostsError> {
    let t = Instant::now();
    loop {
        let c = config("client", &[], &[endpoint])?;
        match zenoh::open(c).wait() {
            Ok(s) => return Ok(s),
            Err(e) if t.elapsed() > patience => {
                return Err(HostsError::Zenoh {
                    what: format!("join {endpoint}"),
                    message: e.to_string(),
                })
            }
            Err(_) => std::thread::sleep(JOIN_RETRY),
        }
    }
}

/// A publisher of one direction of a host's link.
pub fn publisher(
    s: &Session,
    key: String,
) -> Result<zenoh::pubsub::Publisher<'static>, HostsError> {
    s.declare_publisher(key.clone())
        .congestion_control(CongestionControl::Block)
        .express(true)
        .wait()
        .map_err(|e| HostsError::Zenoh {
            what: format!("publish {key}"),
            message: e.to_string(),
        })
}

/// Sends `bytes` on `p`.
pub fn put(p: &zenoh::pubsub::Publisher<'static>, bytes: Vec<u8>) -> Result<(), HostsError> {
    p.put(bytes).wait().map_err(|e| HostsError::Zenoh {
        what: format!("send on {}", p.key_expr()),
        message: e.to_string(),
    })
}

/// Subscribes `key`; `each(key, bytes)` gets every sample.
pub fn subscribe(
    s: &Session,
    key: &str,
    each: impl Fn(String, Vec<u8>) + Send + Sync + 'static,
) -> Result<zenoh::pubsub::Subscriber<()>, HostsError> {
    s.declare_subscriber(key.to_string())
        .callback(move |sample| {
            each(
                sample.key_expr().to_string(),
                sample.payload().to_bytes().into_owned(),
            )
        })
        .wait()
        .map_err(|e| HostsError::Zenoh {
            what: format!("subscribe {key}"),
            message: e.to_string(),
        })
}

/// Watches the liveliness tokens matching `key`: `each(key, true)` when one appears (those
/// already there included), `each(key, false)` when one goes (its process died or left).
pub fn watch(
    s: &Session,
    key: &str,
    each: impl Fn(String, bool) + Send + Sync + 'static,
) -> Result<zenoh::pubsub::Subscriber<()>, HostsError> {
    s.liveliness()
        .declare_subscriber(key.to_string())
        .history(true)
        .callback(move |sample| {
            let alive = sample.kind() == zenoh::sample::SampleKind::Put;
            each(sample.key_expr().to_string(), alive)
        })
        .wait()
        .map_err(|e| HostsError::Zenoh {
            what: format!("watch the liveliness of {key}"),
            message: e.to_string(),
        })
}

/// Declares the liveliness token `key`: it exists while this process and its session live.
pub fn token(s: &Session, key: &str) -> Result<zenoh::liveliness::LivelinessToken, HostsError> {
    s.liveliness()
        .declare_token(key.to_string())
        .wait()
        .map_err(|e| HostsError::Zenoh {
            what: format!("declare the liveliness token {key}"),
            message: e.to_string(),
        })
}
