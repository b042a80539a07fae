//! The world's data services, `world/sense` and `radio/air`, and their remaking when one of
//! their segments shrinks under the world (issue 37 item 4; docs/protocol.md section 4).
//!
//! Both are files in /dev/shm that any process of the user can `ftruncate`. The world writes
//! them every tick under the shrink guard ([`crate::shrink_guard::reading`] with
//! [`crate::shrink_guard::WORLD_DATA`]): a write beyond a truncated file's end writes into a
//! private zero page instead of dying of SIGBUS, and the guard reports it. The world then
//! makes both services anew under the next generation (`world/sense/g1`, `radio/air/g1`, ...),
//! sends the tick's frames into them, raises the barrier's generation word and releases the
//! tick; every agent that finds the word changed opens the new services, and the world sends
//! the tick's frames once more when they are connected (a subscriber gets only what is sent
//! after it connected). Nobody's robot is hurt; the old services are given up.
//!
//! A process that truncates every generation again would keep the world remaking: after
//! [`MAX_REMAKES`] the run ends, failed, with its outputs (the world's error names the cause).

use crate::shrink_guard::{self, WORLD_DATA};
use crate::world::World;
use iceoryx2::prelude::*;
use std::time::{Duration, Instant};
use swarm::barrier::TickBarrier;
use swarm::mailbox::Air;
use swarm::scenario::Scenario;
use swarm::transport::{AirSink, Generation, Result, SenseSink};

/// How many times in a run the world makes its data services anew before it gives up: a
/// truncation is a hostile act of a process of the user; a few are survived, a loop of them
/// ends the run (with its outputs) rather than spending it on remakes.
pub const MAX_REMAKES: u32 = 8;

/// How often the world looks whether every agent opened the new services.
const CONNECT_POLL: Duration = Duration::from_micros(200);

/// The world's `world/sense` and `radio/air` publishers.
pub struct DataPlane {
    senses: SenseSink,
    air: AirSink,
    generation: Generation,
    /// Made anew during this tick's publish: the frames go out again after the release.
    remade: bool,
}

/// The data services shrank under the world more than [`MAX_REMAKES`] times.
#[derive(Debug, thiserror::Error)]
#[error(
    "the world's data services (world/sense, radio/air) shrank under it {0} times (a process \
     of the user truncates their files in /dev/shm): the run ends (docs/protocol.md section 4)"
)]
pub struct TooManyRemakes(u32);

impl DataPlane {
    /// Makes generation 0 of both services.
    pub fn create(node: &Node<ipc::Service>, sc: &Scenario) -> Result<DataPlane> {
        Ok(DataPlane {
            senses: SenseSink::create(node, sc)?,
            air: AirSink::create(node, sc)?,
            generation: 0,
            remade: false,
        })
    }

    /// Publishes tick `k`'s Sense frames of the robots `alive` says are live and the air due
    /// at `k`, before the release; remakes the services when a segment shrank under the write
    /// (and raises the barrier's generation word).
    pub fn publish(
        &mut self,
        (node, sc): (&Node<ipc::Service>, &Scenario),
        barrier: &TickBarrier,
        world: &mut World,
        alive: &[bool],
        sent: &Air,
        k: u64,
    ) -> Result<()> {
        self.remade = false;
        let (senses, air) = (&mut self.senses, &mut self.air);
        let first = shrink_guard::reading(WORLD_DATA, || -> Result<()> {
            senses.publish(k, alive, |i, s| world.sense(i as usize, s))?;
            publish_air(air, world, sent, k)
        });
        match first {
            Some(r) => return r,
            None => self.remake(node, sc, barrier)?,
        }
        // The frames packed once (sensing draws noise: it is not run twice), sent again into
        // the new services until a send goes through.
        while shrink_guard::reading(WORLD_DATA, || self.resend(world, sent, k, alive.len()))
            .transpose()?
            .is_none()
        {
            self.remake(node, sc, barrier)?;
        }
        Ok(())
    }

    /// After the release of tick `k`: when the services were made anew during its publish,
    /// waits (up to `runtime.ack_deadline_ms`) until `agents` agents opened them and sends the
    /// tick's frames again, which they wait for.
    pub fn after_release(
        &mut self,
        (node, sc): (&Node<ipc::Service>, &Scenario),
        barrier: &TickBarrier,
        (world, sent): (&World, &Air),
        k: u64,
        agents: usize,
    ) -> Result<()> {
        if !self.remade {
            return Ok(());
        }
        let until = Instant::now() + Duration::from_millis(sc.runtime.ack_deadline_ms);
        while (self.senses.subscribers() < agents || self.air.subscribers() < agents)
            && Instant::now() < until
        {
            std::thread::sleep(CONNECT_POLL);
        }
        let robots = world.n;
        while shrink_guard::reading(WORLD_DATA, || self.resend(world, sent, k, robots))
            .transpose()?
            .is_none()
        {
            self.remake(node, sc, barrier)?;
        }
        Ok(())
    }

    /// Sends the last packed frames and the air due at `k` again.
    fn resend(&mut self, world: &World, sent: &Air, k: u64, robots: usize) -> Result<()> {
        self.senses.republish(k, robots as u32)?;
        publish_air(&mut self.air, world, sent, k)
    }

    /// Makes both services anew under the next generation and says so in the barrier; the
    /// old ones are given up under the guard (closing touches their segments).
    fn remake(
        &mut self,
        node: &Node<ipc::Service>,
        sc: &Scenario,
        barrier: &TickBarrier,
    ) -> Result<()> {
        if self.generation >= MAX_REMAKES {
            return Err(TooManyRemakes(self.generation).into());
        }
        self.generation += 1;
        let g = self.generation;
        eprintln!(
            "world: a segment of world/sense or radio/air shrank under the world (truncated by a \
             process of the user): both made anew as generation {g} (docs/protocol.md section 4)"
        );
        let mut senses =
            std::mem::replace(&mut self.senses, SenseSink::create_generation(node, sc, g)?);
        self.senses.take_packed(&mut senses);
        let air = std::mem::replace(&mut self.air, AirSink::create_generation(node, sc, g)?);
        shrink_guard::give_up((senses, air));
        barrier.set_data_generation(g);
        self.remade = true;
        Ok(())
    }
}

/// Publishes the messages due at tick `k` as one air (`swarm::air`) through the run's air
/// service (`radio/air`), before the tick is released: every agent reads its list in it. The
/// world lends its airs (`World::lend_air`): the payloads are copied from `sent`, the buffer
/// of the last tick's messages, which is not touched between `World::apply` and this publish.
fn publish_air(air: &mut AirSink, world: &World, sent: &Air, k: u64) -> Result<()> {
    let len = swarm::air::air_len(world.air(), world.n);
    air.publish(len, |out| {
        swarm::air::write_air_from(world.air(), sent.bytes(), world.n, k, out)
    })?;
    Ok(())
}
