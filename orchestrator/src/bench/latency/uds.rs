//! The copying baseline: the bytes variant of the radio's message bincode-encoded into a
//! buffer, written to a Unix domain socket, read and decoded (the payload copied four times:
//! encode, write, read, decode). Busy-poll reads with MSG_DONTWAIT and spins; blocking-wake
//! sleeps in recv(2).

use super::radio::{data_len_for, BytesPing, Payload};
use super::wait::wait_for;
use super::{Mode, Parent, Peer, READY_S};
use crate::bench::{now_ns, spawn_child, tick, BenchError, BenchResult, ChildArgs};
use serde::Serialize;
use std::io::Write;
use std::os::fd::AsRawFd;
use std::os::linux::net::SocketAddrExt;
use std::os::unix::net::{SocketAddr, UnixListener, UnixStream};
use std::time::{Duration, Instant};

fn uds_error(what: &'static str) -> impl FnOnce(std::io::Error) -> BenchError {
    move |source| BenchError::Uds { what, source }
}

/// The cell's socket: an abstract name made from the run's prefix (nothing in the file system).
fn address(prefix: &str) -> BenchResult<SocketAddr> {
    SocketAddr::from_abstract_name(format!("{prefix}lat-uds").as_bytes())
        .map_err(uds_error("address"))
}

/// The parent: listens, lets the child connect, then pings and records the pong's one-hop time.
pub(super) fn parent(p: &Parent) -> BenchResult<Vec<u64>> {
    let addr = address(p.prefix)?;
    let listener = UnixListener::bind_addr(&addr).map_err(uds_error("bind"))?;
    listener
        .set_nonblocking(true)
        .map_err(uds_error("set_nonblocking"))?;
    let mut child = spawn_child(p.kind, (p.prefix, p.fds), 1, p.extra, false)?;
    let t = Instant::now();
    let mut stream = loop {
        match listener.accept() {
            Ok((s, _)) => break s,
            Err(x) if x.kind() == std::io::ErrorKind::WouldBlock => {
                if t.elapsed() > Duration::from_secs(READY_S)
                    || matches!(child.try_wait(), Ok(Some(_)))
                {
                    let _ = child.kill();
                    let _ = child.wait();
                    return Err(p.not_ready());
                }
                std::thread::sleep(Duration::from_micros(200));
            }
            Err(x) => return Err(uds_error("accept")(x)),
        }
    };
    stream
        .set_nonblocking(false)
        .map_err(uds_error("set_nonblocking"))?;
    let data = vec![0xa5; data_len_for::<BytesPing>(p.size)];
    let (mut wbuf, mut rbuf) = (Vec::new(), Vec::new());
    let mut ns = Vec::with_capacity(p.total as usize);
    let r = (|| -> BenchResult<()> {
        for _ in 0..p.total {
            let ping = BytesPing::make(now_ns(), data.clone());
            send(&mut stream, &mut wbuf, &ping)?;
            recv(&stream, &mut rbuf, p.mode, Peer::Child)?;
            let (pong, _): (BytesPing, usize) =
                bincode::serde::decode_from_slice(&rbuf, bincode::config::standard())?;
            ns.push(now_ns().saturating_sub(pong.stamp));
        }
        Ok(())
    })();
    drop(stream);
    tick::reap_children(vec![child]);
    r?;
    Ok(ns)
}

/// The child: connects, and answers each ping with its data under a fresh stamp.
pub(super) fn child(a: &ChildArgs, mode: Mode) -> BenchResult<()> {
    let addr = address(&a.prefix)?;
    let mut stream = UnixStream::connect_addr(&addr).map_err(uds_error("connect"))?;
    let (mut wbuf, mut rbuf) = (Vec::new(), Vec::new());
    for _ in 0..a.rounds {
        recv(&stream, &mut rbuf, mode, Peer::Parent)?;
        let (ping, _): (BytesPing, usize) =
            bincode::serde::decode_from_slice(&rbuf, bincode::config::standard())?;
        let data = ping.data.0;
        send(&mut stream, &mut wbuf, &BytesPing::make(now_ns(), data))?;
    }
    Ok(())
}

/// Frame: u32 little-endian length, then the bincode bytes.
fn send<M: Serialize>(s: &mut UnixStream, buf: &mut Vec<u8>, m: &M) -> BenchResult<()> {
    buf.clear();
    buf.extend_from_slice(&[0; 4]);
    bincode::serde::encode_into_std_write(m, buf, bincode::config::standard())?;
    let n = (buf.len() - 4) as u32;
    buf[..4].copy_from_slice(&n.to_le_bytes());
    s.write_all(buf).map_err(uds_error("write"))
}

/// Reads one frame into `buf`.
fn recv(s: &UnixStream, buf: &mut Vec<u8>, mode: Mode, peer: Peer) -> BenchResult<()> {
    let mut len = [0u8; 4];
    read_full(s, &mut len, mode, peer)?;
    buf.resize(u32::from_le_bytes(len) as usize, 0);
    read_full(s, buf, mode, peer)
}

/// Reads exactly `b.len()` bytes; busy-poll never sleeps in the kernel (MSG_DONTWAIT, and
/// the shared wait loop spins), blocking-wake blocks in recv(2) (the loop's sleep is empty).
fn read_full(s: &UnixStream, b: &mut [u8], mode: Mode, peer: Peer) -> BenchResult<()> {
    let fd = s.as_raw_fd();
    let flags = match mode {
        Mode::Poll => libc::MSG_DONTWAIT,
        Mode::Block => 0,
    };
    if b.is_empty() {
        return Ok(());
    }
    let mut at = 0;
    wait_for(
        mode,
        peer,
        || {
            // SAFETY: recv into the unfilled tail of a live buffer.
            let n = unsafe {
                libc::recv(
                    fd,
                    b[at..].as_mut_ptr() as *mut libc::c_void,
                    b.len() - at,
                    flags,
                )
            };
            if n > 0 {
                at += n as usize;
            } else if n == 0 {
                return Err(BenchError::UdsClosed);
            } else {
                let err = std::io::Error::last_os_error();
                match err.kind() {
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::Interrupted => {}
                    _ => return Err(uds_error("recv")(err)),
                }
            }
            Ok((at == b.len()).then_some(()))
        },
        || Ok(()),
    )
}
