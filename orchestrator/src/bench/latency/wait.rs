//! The one wait loop of every path: try to take the message; if it is not there, spin once
//! (busy-poll) or sleep until the sender's wake-up (blocking-wake); give up after `TIMEOUT`.

use super::super::{BenchError, BenchResult};
use super::Mode;
use crate::bench::error::Peer;
use std::time::{Duration, Instant};

/// How long one wait may take before the cell is abandoned.
pub(super) const TIMEOUT: Duration = Duration::from_secs(10);

/// How long one blocking sleep lasts at most before the receiver looks again (the sender's
/// wake-up normally ends it far earlier).
pub(super) const NAP: Duration = Duration::from_millis(500);

/// Calls `take` until it yields; between tries spins once (`Mode::Poll`) or calls `sleep`
/// (`Mode::Block`). The time-out is checked after every sleep, and every 4,096 spins (reading
/// the clock is not free next to a spin).
pub(super) fn wait_for<T>(
    mode: Mode,
    peer: Peer,
    take: impl FnMut() -> BenchResult<Option<T>>,
    sleep: impl FnMut() -> BenchResult<()>,
) -> BenchResult<T> {
    wait_within(TIMEOUT, mode, peer, take, sleep)
}

/// `wait_for` with its own time-out.
fn wait_within<T>(
    timeout: Duration,
    mode: Mode,
    peer: Peer,
    mut take: impl FnMut() -> BenchResult<Option<T>>,
    mut sleep: impl FnMut() -> BenchResult<()>,
) -> BenchResult<T> {
    let since = Instant::now();
    let mut spins = 0u32;
    loop {
        if let Some(x) = take()? {
            return Ok(x);
        }
        match mode {
            Mode::Block => sleep()?,
            Mode::Poll => std::hint::spin_loop(),
        }
        spins += 1;
        if (mode == Mode::Block || spins.is_multiple_of(4096)) && since.elapsed() > timeout {
            return Err(BenchError::Timeout(peer));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn takes_on_the_third_try_sleeping_twice() {
        let (mut tries, mut sleeps) = (0, 0);
        let got = wait_for(
            Mode::Block,
            Peer::Child,
            || {
                tries += 1;
                Ok((tries == 3).then_some(tries))
            },
            || {
                sleeps += 1;
                Ok(())
            },
        )
        .unwrap();
        assert_eq!((got, tries, sleeps), (3, 3, 2));
    }

    #[test]
    fn polling_never_sleeps() {
        let mut tries = 0;
        wait_for(
            Mode::Poll,
            Peer::Parent,
            || {
                tries += 1;
                Ok((tries == 5000).then_some(()))
            },
            || panic!("a poll does not sleep"),
        )
        .unwrap();
        assert_eq!(tries, 5000);
    }

    #[test]
    fn a_failed_take_or_sleep_ends_the_wait() {
        let e = wait_for::<()>(
            Mode::Block,
            Peer::Child,
            || Ok(None),
            || Err(BenchError::UdsClosed),
        )
        .unwrap_err();
        assert!(matches!(e, BenchError::UdsClosed));
        let e = wait_for::<()>(
            Mode::Poll,
            Peer::Child,
            || Err(BenchError::UdsClosed),
            || Ok(()),
        )
        .unwrap_err();
        assert!(matches!(e, BenchError::UdsClosed));
    }

    #[test]
    fn times_out_naming_the_peer() {
        let mut sleeps = 0;
        let e = wait_within::<()>(
            Duration::from_millis(50),
            Mode::Block,
            Peer::Parent,
            || Ok(None),
            || {
                sleeps += 1;
                std::thread::sleep(Duration::from_millis(20));
                Ok(())
            },
        )
        .unwrap_err();
        assert!(matches!(e, BenchError::Timeout(Peer::Parent)), "{e}");
        // Each sleep lasts at least 20 ms, so 50 ms have passed after the third at the latest
        // (sooner when the machine is busy and a sleep overshoots).
        assert!((1..=3).contains(&sleeps), "{sleeps} sleeps");
        assert_eq!(e.to_string(), "timed out waiting for the parent");
    }
}
