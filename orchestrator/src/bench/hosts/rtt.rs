//! The round trip of a link: a TCP echo between two network namespaces, measured in this
//! process. [chosen] The sockets are made by short threads that entered the namespaces with
//! setns (a socket stays in the namespace it was made in, whichever thread uses it after):
//! no helper process, no Python, and the bench keeps the figures as numbers; the bench's own
//! threads stay in its namespace.

use super::error::HostsBenchError;
use super::net::Netns;
use std::io::{Read, Write};
use std::net::{Ipv4Addr, SocketAddr, TcpListener, TcpStream};
use std::time::{Duration, Instant};

/// Bytes of each echo: a small message, as a tick's batch of a few robots is. [chosen]
const MESSAGE_BYTES: usize = 64;
/// Round trips measured (the median is reported).
const ROUNDS: usize = 200;
/// Round trips before those, not measured (connection and caches warm).
const WARMUP: usize = 20;
/// The longest a connect, a read or a write may take before the measure fails (far above
/// any delay the rows add).
const IO_LIMIT: Duration = Duration::from_secs(5);

/// How often a waiting accept looks again.
const ACCEPT_POLL: Duration = Duration::from_millis(1);

/// The first connection to `listener` within `limit` (so a client that never comes does
/// not hold the server's thread for ever).
fn accept_within(listener: &TcpListener, limit: Duration) -> std::io::Result<TcpStream> {
    listener.set_nonblocking(true)?;
    let t = Instant::now();
    loop {
        match listener.accept() {
            Ok((c, _)) => {
                c.set_nonblocking(false)?;
                return Ok(c);
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock && t.elapsed() < limit => {
                std::thread::sleep(ACCEPT_POLL);
            }
            Err(e) => return Err(e),
        }
    }
}

/// Runs `f` on a thread of its own inside `ns`.
fn in_netns<T: Send>(
    ns: &Netns,
    f: impl FnOnce() -> std::io::Result<T> + Send,
    addr: &str,
) -> Result<T, HostsBenchError> {
    std::thread::scope(|s| {
        s.spawn(|| {
            ns.enter()?;
            f().map_err(|source| HostsBenchError::Rtt {
                addr: addr.to_string(),
                source,
            })
        })
        .join()
        .expect("the socket thread does not panic")
    })
}

/// The median round trip (ms) of a TCP echo (TCP_NODELAY) from `from`'s namespace to a
/// server at `to_addr` in `to`'s namespace.
pub fn measure(from: &Netns, to: &Netns, to_addr: Ipv4Addr) -> Result<f64, HostsBenchError> {
    let label = to_addr.to_string();
    let rtt_err = |source| HostsBenchError::Rtt {
        addr: label.clone(),
        source,
    };
    let listener = in_netns(to, || TcpListener::bind((to_addr, 0)), &label)?;
    let at: SocketAddr = listener.local_addr().map_err(rtt_err)?;
    let server = std::thread::spawn(move || -> std::io::Result<()> {
        let mut c = accept_within(&listener, IO_LIMIT)?;
        c.set_nodelay(true)?;
        c.set_read_timeout(Some(IO_LIMIT))?;
        let mut buf = [0u8; MESSAGE_BYTES];
        loop {
            match c.read(&mut buf)? {
                0 => return Ok(()),
                k => c.write_all(&buf[..k])?,
            }
        }
    });
    let result = (|| {
        let mut c = in_netns(from, || TcpStream::connect_timeout(&at, IO_LIMIT), &label)?;
        c.set_nodelay(true).map_err(rtt_err)?;
        c.set_read_timeout(Some(IO_LIMIT)).map_err(rtt_err)?;
        c.set_write_timeout(Some(IO_LIMIT)).map_err(rtt_err)?;
        let msg = [0x5au8; MESSAGE_BYTES];
        let mut back = [0u8; MESSAGE_BYTES];
        let mut ns = Vec::with_capacity(ROUNDS);
        for k in 0..WARMUP + ROUNDS {
            let t = Instant::now();
            c.write_all(&msg).map_err(rtt_err)?;
            c.read_exact(&mut back).map_err(rtt_err)?;
            if k >= WARMUP {
                ns.push(t.elapsed().as_nanos() as u64);
            }
        }
        ns.sort_unstable();
        Ok(ns[ns.len() / 2] as f64 / 1e6)
    })();
    // The client is closed (dropped) by now: the server reads end of file and returns.
    let served = server.join().expect("the echo thread does not panic");
    let rtt = result?;
    served.map_err(rtt_err)?;
    Ok(rtt)
}
