//! A host proxy's local world: the services its agents open (`world/sense`, `radio/air`, its
//! robots' `robot/<i>/act`) and the tick barrier, made with the run's scenario as the world
//! makes them, under the proxy's own iceoryx2 prefix. The Sense and air bytes are published
//! as they came over the link; the act samples are read back raw, attach notices apart.
//!
//! The barrier is the run's as the orchestrator makes it (two sealed memfds,
//! docs/protocol.md section 4): the proxy is world and orchestrator in one process, so it
//! seals the world's segment as soon as it made it, before any agent starts, and keeps the
//! descriptors for every agent it starts.

use super::wire::Act;
use super::HostsError;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use swarm::barrier::{BarrierFds, TickBarrier};
use swarm::frames::{Action, AirHeader, SenseHeader};
use swarm::scenario::Scenario;
use swarm::transport::{self, ActService, SensesService};

type ActSample = iceoryx2::sample::Sample<ipc::Service, [u8], Action>;

pub struct LocalWorld {
    pub node: Node<ipc::Service>,
    pub barrier: TickBarrier,
    /// The barrier's memfds, inherited by every agent the proxy starts.
    pub barrier_fds: BarrierFds,
    senses: Publisher<ipc::Service, [u8], SenseHeader>,
    air: transport::AirSink,
    /// Per robot of the run: its act subscriber if it runs here, and its newest sample.
    acts: Vec<Option<Subscriber<ipc::Service, [u8], Action>>>,
    held: Vec<Option<ActSample>>,
    /// Per robot: the highest attach number an attach notice on its act service carried.
    attached: Vec<u64>,
    _services: (SensesService, Vec<ActService>),
}

impl LocalWorld {
    /// Makes the services and the barrier for `robots` of the run `sc` under `prefix`.
    pub fn create(sc: &Scenario, prefix: &str, robots: &[u32]) -> Result<LocalWorld, HostsError> {
        let config = transport::run_config(prefix)?;
        let node = transport::node(&config, "world")?;
        let senses_svc = transport::senses_service(&node, sc, true)?;
        let senses = transport::senses_publisher(&senses_svc, sc)?;
        let air = transport::AirSink::create(&node, sc)?;
        let n = sc.run.robots as usize;
        let mut acts: Vec<Option<_>> = (0..n).map(|_| None).collect();
        let mut services = Vec::new();
        for &r in robots {
            let svc = transport::act_service(&node, r, true)?;
            acts[r as usize] = Some(transport::act_subscriber(&svc)?);
            services.push(svc);
        }
        let (barrier, barrier_fds) = TickBarrier::create(prefix, sc.run.robots)?;
        // Mapped writable once, here (world and orchestrator are this process): sealed
        // before any agent exists.
        barrier_fds.seal_worlds_segment()?;
        Ok(LocalWorld {
            node,
            barrier,
            barrier_fds,
            attached: vec![0; n],
            senses,
            air,
            acts,
            held: (0..n).map(|_| None).collect(),
            _services: (senses_svc, services),
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

    /// Receives what robot `r`'s act service holds: attach notices are noted, the newest
    /// action is held.
    fn receive(&mut self, r: u32) {
        let Some(Some(sub)) = self.acts.get(r as usize) else {
            return;
        };
        while let Ok(Some(s)) = sub.receive() {
            match transport::attach_of(s.user_header()) {
                Some(n) => self.attached[r as usize] = self.attached[r as usize].max(n),
                None => self.held[r as usize] = Some(s),
            }
        }
    }

    /// The highest attach number an attach notice of robot `r`'s act service carried (0:
    /// none yet). An agent's notice is the first sample it sends, before any action.
    pub fn attached(&mut self, r: u32) -> u64 {
        self.receive(r);
        self.attached.get(r as usize).copied().unwrap_or(0)
    }

    /// Whether robot `r`'s act service holds its action of tick `k`.
    pub fn arrived(&mut self, r: u32, k: u64) -> bool {
        self.receive(r);
        self.held
            .get(r as usize)
            .is_some_and(|h| h.as_ref().is_some_and(|s| s.user_header().tick == k))
    }

    /// Robot `r`'s action of tick `k` with its used message area, if it arrived.
    pub fn take(&mut self, r: u32, k: u64) -> Option<Act> {
        if !self.arrived(r, k) {
            return None;
        }
        let s = self.held[r as usize].take()?;
        let used = (s.user_header().radio_bytes as usize).min(s.payload().len());
        Some(Act {
            robot: r,
            action: *s.user_header(),
            area: s.payload()[..used].to_vec(),
        })
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
