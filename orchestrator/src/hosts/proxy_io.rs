//! A host proxy's local world: the services its agents open (`world/sense`, `radio/air`, its
//! robots' act services, `robot/<i>/act` or `robot/<i>/board`) and the tick barrier, made with
//! the run's scenario as the world makes them, under the proxy's own iceoryx2 prefix. The
//! Sense and air bytes are published as they came over the link; the actions are read back
//! with their message areas as written (`ActSource::take_area`).
//!
//! The barrier is the run's as the orchestrator makes it (two sealed memfds,
//! docs/protocol.md section 4): the proxy is world and orchestrator in one process, so it
//! seals the world's segment as soon as it made it, before any agent starts, and keeps the
//! descriptors for every agent it starts.

use super::wire::Act;
use super::HostsError;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::prelude::*;
use swarm::barrier::{BarrierFds, TickBarrier};
use swarm::frames::{AirHeader, SenseHeader};
use swarm::scenario::Scenario;
use swarm::transport::{self, SensesService};

pub struct LocalWorld {
    pub node: Node<ipc::Service>,
    pub barrier: TickBarrier,
    /// The barrier's memfds, inherited by every agent the proxy starts.
    pub barrier_fds: BarrierFds,
    senses: Publisher<ipc::Service, [u8], SenseHeader>,
    air: transport::AirSink,
    /// Its robots' act services (`runtime.acts`: pub-sub or blackboards), read as the world
    /// reads them; the actions are relayed with their message areas as written.
    acts: transport::ActSource,
    _services: SensesService,
}

impl LocalWorld {
    /// Makes the services and the barrier for `robots` of the run `sc` under `prefix`.
    pub fn create(sc: &Scenario, prefix: &str, robots: &[u32]) -> Result<LocalWorld, HostsError> {
        let config = transport::run_config(prefix)?;
        let node = transport::node(&config, "world")?;
        let senses_svc = transport::senses_service(&node, sc, 0, true)?;
        let senses = transport::senses_publisher(&senses_svc, sc)?;
        let air = transport::AirSink::create(&node, sc)?;
        let acts = transport::ActSource::create_for(&node, sc, robots)?;
        let (barrier, barrier_fds) = TickBarrier::create(prefix, sc.run.robots)?;
        // Mapped writable once, here (world and orchestrator are this process): sealed
        // before any agent exists.
        barrier_fds.seal_worlds_segment()?;
        Ok(LocalWorld {
            node,
            barrier,
            barrier_fds,
            senses,
            air,
            acts,
            _services: senses_svc,
        })
    }

    /// Publishes tick `tick`'s Sense records (a `world/sense` payload of the run's robots)
    /// and its air, as they came.
    pub fn publish(
        &mut self,
        tick: u64,
        robots: u32,
        sense: &[u8],
        air_header: AirHeader,
        air: &[u8],
    ) -> Result<(), HostsError> {
        let sample = self
            .senses
            .loan_slice_uninit(sense.len())
            .map_err(|e| HostsError::Other(format!("world/sense loan: {e:?}")))?;
        let mut sample = sample.write_from_slice(sense);
        *sample.user_header_mut() = SenseHeader {
            tick,
            robots,
            bytes: sense.len() as u32,
        };
        sample
            .send()
            .map_err(|e| HostsError::Other(format!("world/sense send: {e:?}")))?;
        self.air.publish(air.len(), |out| {
            out.copy_from_slice(air);
            air_header
        })?;
        Ok(())
    }

    /// The highest attach number robot `r`'s act service showed (0: none yet).
    pub fn attached(&mut self, r: u32) -> u64 {
        self.acts.attached(&self.node, r)
    }

    /// Whether robot `r`'s act service holds its action of tick `k`.
    pub fn arrived(&mut self, r: u32, k: u64) -> bool {
        self.acts.arrived(r, k)
    }

    /// Robot `r`'s action of tick `k` with its used message area, if it arrived.
    pub fn take(&mut self, r: u32, k: u64) -> Option<Act> {
        let (action, area) = self.acts.take_area(r, k)?;
        Some(Act {
            robot: r,
            action,
            area,
        })
    }

    /// Robot `r`'s agent died: its act service is let go of if it must be made anew for a
    /// replacement (a blackboard, `ActSource::retire`).
    pub fn retire(&mut self, r: u32) {
        self.acts.retire(r)
    }
}

/// The robots with a record in a `world/sense` payload (docs/protocol.md 3.1: the index's
/// entries with a length).
pub fn robots_in(sense: &[u8]) -> Vec<u32> {
    let u32_at = |at: usize| -> Option<u32> {
        Some(u32::from_le_bytes(sense.get(at..at + 4)?.try_into().ok()?))
    };
    let n = u32_at(0).unwrap_or(0);
    (0..n)
        .filter(|&r| u32_at(8 + 8 * r as usize + 4).is_some_and(|len| len > 0))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_robots_of_a_packed_sense_are_those_with_a_record() {
        let mut p = swarm::sense_pack::SensePacker::default();
        p.begin(6);
        let s = swarm::frames::Sense::zeroed();
        p.push(1, &s);
        p.push(4, &s);
        assert_eq!(robots_in(p.bytes()), vec![1, 4]);
        assert!(robots_in(&[]).is_empty());
    }
}
