//! The runtime's Sense path: a whole Sense frame (every list full), loaned with
//! `loan_uninit`, written in place, sent, and read in place by the receiver, as the world and
//! an agent do it. The parent's Action frame is the child's cue for the next frame.

use super::{open_barrier, wait_parent, Mode, Parent};
use crate::bench::{now_ns, tick, BenchResult, ChildArgs};
use swarm::frames::Action;
use swarm::scenario::Scenario;
use swarm::transport::{self, ServiceId, TransportError};

/// Robot 0's services, which the cell uses.
const SENSE: ServiceId = ServiceId::Sense(0);
const ACT: ServiceId = ServiceId::Act(0);

/// The parent: sends an Action frame each round (the child's cue), then waits for the Sense
/// frame the child writes in place and reads it in place.
pub(super) fn parent(p: &Parent) -> BenchResult<Vec<u64>> {
    let config = transport::run_config(p.prefix)?;
    let node = transport::node(&config, "bench-lat-0")?;
    let sense_svc = transport::sense_service(&node, 0, true)?;
    let act_svc = transport::act_service(&node, 0, true)?;
    let sub = sense_svc
        .subscriber_builder()
        .buffer_size(1)
        .create()
        .map_err(|source| TransportError::Subscriber {
            service: SENSE,
            source,
        })?;
    let act = transport::act_publisher(&act_svc, &Scenario::default())?;
    let child = p.spawn()?;
    let mut ns = Vec::with_capacity(p.total as usize);
    let mut done = 1;
    let mut check = 0usize;
    let r = (|| -> BenchResult<()> {
        for r in 0..p.total {
            let cue = act
                .loan_slice_uninit(8)
                .map_err(|source| TransportError::Loan {
                    service: ACT,
                    source,
                })?;
            // SAFETY: shared memory is always initialised bytes; nobody reads the slice.
            let mut cue = unsafe { cue.assume_init() };
            *cue.user_header_mut() = Action::idle(r, 0);
            cue.send().map_err(|source| TransportError::Send {
                service: ACT,
                source,
            })?;
            if p.mode == Mode::Block {
                p.barrier.ack(0, r);
            }
            p.wait(&mut done, || {
                let s = sub.receive().map_err(|source| TransportError::Receive {
                    service: SENSE,
                    source,
                })?;
                let Some(s) = s else {
                    return Ok(None);
                };
                // Read in place: the stamp, and the lists' lengths as an agent would.
                let stamp = s.tick;
                check += s.nearby().len() + s.obstacle_points().len();
                ns.push(now_ns().saturating_sub(stamp));
                Ok(Some(()))
            })?;
        }
        Ok(())
    })();
    tick::reap_children(vec![child]);
    r?;
    std::hint::black_box(check);
    Ok(ns)
}

/// The child: on each Action frame, writes a full Sense frame in place (as the world does)
/// with its stamp, and sends it.
pub(super) fn child(a: &ChildArgs, mode: Mode) -> BenchResult<()> {
    let barrier = open_barrier()?;
    let config = transport::run_config(&a.prefix)?;
    let node = transport::node(&config, "bench-lat-1")?;
    let sense_svc = transport::sense_service(&node, 0, false)?;
    let act_svc = transport::act_service(&node, 0, false)?;
    let sense_pub =
        sense_svc
            .publisher_builder()
            .create()
            .map_err(|source| TransportError::Publisher {
                service: SENSE,
                source,
            })?;
    let act_sub =
        act_svc
            .subscriber_builder()
            .create()
            .map_err(|source| TransportError::Subscriber {
                service: ACT,
                source,
            })?;
    barrier.mark_ready(1);
    for r in 0..a.rounds {
        wait_parent(&barrier, mode, || {
            let got = act_sub
                .receive()
                .map_err(|source| TransportError::Receive {
                    service: ACT,
                    source,
                })?;
            Ok(got.map(|_| ()))
        })?;
        let stamp = now_ns();
        let mut sample = sense_pub
            .loan_uninit()
            .map_err(|source| TransportError::Loan {
                service: SENSE,
                source,
            })?;
        let p = sample.payload_mut().as_mut_ptr();
        // SAFETY: Sense is plain old data, valid when zeroed. As the world does, the fixed part
        // is zeroed and then every field is written through a reference; here every list is
        // written in full (the largest frame).
        let s = unsafe {
            std::ptr::write_bytes(p as *mut u8, 0, swarm::frames::SENSE_FIXED_BYTES);
            &mut *p
        };
        s.tick = stamp;
        s.robot = 0;
        s.pos = [r as f64, 1.0];
        s.heading = 0.5;
        s.vel = [1.0, 0.0];
        s.alive_robots = 128;
        s.fill_every_list(r as f64);
        // SAFETY: every byte written above.
        let sample = unsafe { sample.assume_init() };
        sample.send().map_err(|source| TransportError::Send {
            service: SENSE,
            source,
        })?;
        if mode == Mode::Block {
            barrier.release(r + 1, 1);
        }
    }
    Ok(())
}
