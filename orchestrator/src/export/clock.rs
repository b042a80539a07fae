//! Simulated time: how long a tick of a run lasts in the world it simulates, from its
//! scenario. The hunt says so (`hunt.params.minutes_per_tick`: 0.05 min, 3 s); the other
//! missions' scenarios name no unit of time, and a tick is shown as one second. Pacing
//! (`runtime.tick_hz`) is wall-clock speed, not simulated time, and plays no part.

use swarm::scenario::Scenario;

/// A tick of a scenario that names no unit of time, shown as this many seconds.
pub const UNITLESS_TICK_SECONDS: f64 = 1.0;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimClock {
    /// Simulated seconds per tick.
    pub seconds_per_tick: f64,
    /// Where that figure comes from (the scenario key, or why none), for the files' metadata.
    pub source: &'static str,
}

impl SimClock {
    pub fn of(sc: &Scenario) -> SimClock {
        let mission = world::mission::entry_for(sc).map_or("", |m| m.name);
        if mission == "hunt" {
            SimClock {
                seconds_per_tick: sc.hunt().params.minutes_per_tick * 60.0,
                source: "hunt.params.minutes_per_tick x 60",
            }
        } else {
            SimClock {
                seconds_per_tick: UNITLESS_TICK_SECONDS,
                source: "the scenario names no unit of time: one tick is shown as one second",
            }
        }
    }
    /// Simulated seconds at the end of tick `tick` (tick 0: the start).
    pub fn seconds(&self, tick: u64) -> f64 {
        tick as f64 * self.seconds_per_tick
    }
    /// The same in nanoseconds (MCAP's log time).
    pub fn ns(&self, tick: u64) -> u64 {
        (self.seconds(tick) * 1e9).round() as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hunt_tick_is_its_minutes_and_other_ticks_a_second() {
        let mut sc = Scenario::default();
        let c = SimClock::of(&sc);
        assert_eq!(c.seconds_per_tick, UNITLESS_TICK_SECONDS);
        assert_eq!(c.ns(265), 265_000_000_000);
        sc.run.behaviour = "hunt".into();
        sc.hunt_mut().params.minutes_per_tick = 0.05;
        let c = SimClock::of(&sc);
        assert!((c.seconds_per_tick - 3.0).abs() < 1e-12);
        assert_eq!(c.ns(100), 300_000_000_000);
    }
}
