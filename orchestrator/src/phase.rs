//! The in-process executor's thread barrier: all its worker threads meet here twice a tick.
//!
//! `std::sync::Barrier` puts every waiter to sleep, and each tick then paid two futex wake-ups
//! per worker (~7 % of a 2-thread search run in the kernel). Here a waiter first spins for a
//! short while (the other threads are running the same tick, so it usually ends within
//! microseconds) and only then sleeps on a futex. The run's thread count never exceeds the
//! machine's cores by default, so the spinning takes no core another thread needs.

use std::hint::spin_loop;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};
use swarm::barrier::{futex_wait, futex_wake};

/// How long a waiter spins before it sleeps. [chosen] About a tenth of a 100-robot search tick
/// on one thread; longer than the serial part of most ticks.
const SPIN: Duration = Duration::from_micros(50);

/// A reusable barrier for `n` threads (a generation count: the last to arrive starts the next).
pub struct PhaseBarrier {
    n: u32,
    arrived: AtomicU32,
    generation: AtomicU32,
    sleepers: AtomicU32,
}

impl PhaseBarrier {
    pub fn new(n: usize) -> PhaseBarrier {
        PhaseBarrier {
            n: n.max(1) as u32,
            arrived: AtomicU32::new(0),
            generation: AtomicU32::new(0),
            sleepers: AtomicU32::new(0),
        }
    }

    /// Returns once all `n` threads have called `wait` for this generation.
    pub fn wait(&self) {
        let gen = self.generation.load(Ordering::Acquire);
        if self.arrived.fetch_add(1, Ordering::AcqRel) + 1 == self.n {
            // Reset before the generation moves on: a thread that sees the new generation may
            // arrive at the next one straight away.
            self.arrived.store(0, Ordering::Relaxed);
            // SeqCst here and on `sleepers` below: a waiter counts itself a sleeper before its
            // futex re-reads the generation, the waker moves the generation before it reads
            // the sleepers, so one of them sees the other (else the 100 ms timeout ends it).
            self.generation.fetch_add(1, Ordering::SeqCst);
            if self.sleepers.load(Ordering::SeqCst) > 0 {
                futex_wake(&self.generation, i32::MAX);
            }
            return;
        }
        let t0 = Instant::now();
        let mut spins = 0u32;
        while self.generation.load(Ordering::Acquire) == gen {
            if spins < u32::MAX && (!spins.is_multiple_of(64) || t0.elapsed() < SPIN) {
                spins += 1;
                spin_loop();
                continue;
            }
            spins = u32::MAX;
            self.sleepers.fetch_add(1, Ordering::SeqCst);
            // Returns at once if the generation has moved on since the check above.
            futex_wait(&self.generation, gen, Duration::from_millis(100));
            self.sleepers.fetch_sub(1, Ordering::AcqRel);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicU64;

    #[test]
    fn no_thread_passes_a_generation_before_all_arrive() {
        // Each thread adds to the counter between two waits; after the second wait every
        // thread must see all additions of the round, whether it spun or slept.
        for threads in [1usize, 2, 3, 5] {
            let b = PhaseBarrier::new(threads);
            let count = AtomicU64::new(0);
            std::thread::scope(|s| {
                for t in 0..threads {
                    let (b, count) = (&b, &count);
                    s.spawn(move || {
                        for round in 1..=200u64 {
                            if t == 0 && round % 50 == 0 {
                                // Long enough for the others to stop spinning and sleep.
                                std::thread::sleep(Duration::from_millis(1));
                            }
                            count.fetch_add(1, Ordering::SeqCst);
                            b.wait();
                            assert_eq!(count.load(Ordering::SeqCst), round * threads as u64);
                            b.wait();
                        }
                    });
                }
            });
        }
    }
}
