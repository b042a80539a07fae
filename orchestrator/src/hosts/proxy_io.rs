//! A host proxy's local world: the services its agents open (`world/sense`, `radio/air`, its
//! robots' `robot/<i>/act`) and the tick barrier, made with the run's scenario as the world
//! makes them, under the proxy's own iceoryx2 prefix. The Sense and air bytes are published
//! as they came over the link; the act samples are read back raw.

use super::wire::Act;
use super::HostsError;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use swarm::barrier::TickBarrier;
use swarm::frames::{Action, AirHeader, SenseHeader};
use swarm::scenario::Scenario;
use swarm::transport::{self, ActService, SensesService};

type ActSample = iceoryx2::sample::Sample<ipc::Service, [u8], Action>;

pub struct LocalWorld {
    pub node: Node<ipc::Service>,
    pub barrier: TickBarrier,
    senses: Publisher<ipc::Service, [u8], SenseHeader>,
    air: transport::AirSink,
    /// Per robot of the run: its act subscriber if it runs here, and its newest sample.
    acts: Vec<Option<Subscriber<ipc::Service, [u8], Action>>>,
    held: Vec<Option<ActSample>>,
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
        let barrier = TickBarrier::create(prefix, sc.run.robots)?;
        Ok(LocalWorld {
            node,
            barrier,
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

    /// Whether robot `r`'s act service holds its action of tick `k`.
    pub fn arrived(&mut self, r: u32, k: u64) -> bool {
        let Some(Some(sub)) = self.acts.get(r as usize) else {
            return false;
        };
        while let Ok(Some(s)) = sub.receive() {
            self.held[r as usize] = Some(s);
        }
        self.held[r as usize]
            .as_ref()
            .is_some_and(|s| s.user_header().tick == k)
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
