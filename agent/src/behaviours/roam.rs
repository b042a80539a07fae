//! Roaming by virtual force (search paper, docs/search.md 2.3-2.4): full speed along the net
//! repulsion from the two nearest robots *heard on the radio*, plus repulsion from obstacle
//! and wall points the robot senses. Each robot broadcasts its position every tick.

use crate::kernels::virtual_force;
#[path = "roam_nearest.rs"]
mod nearest;
use nearest::Nearest;
use rand::Rng;
use serde::{Deserialize, Serialize};
use swarm::scenario::{Check, ConfigError, RoamParams, Scenario, ROAM_BEACON_OVERHEAD};
use swarm::streams;
use swarm::{Behaviour, Blob, Command, Outbox, Received, Sense};

/// The position beacon every roaming robot broadcasts.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Beacon {
    pub pos: [f64; 2],
}

/// A beacon with `roam.payload_bytes` of bulk payload (a camera frame, say), received in
/// place (zero-copy). A type of its own so that position-only beacons stay as small as before
/// (a Blob field in every beacon cost roam ~2.5 % of its ticks/s at N = 50).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct BulkBeacon {
    pub pos: [f64; 2],
    pub payload: Blob,
}

/// What a roaming robot can broadcast.
pub trait BeaconMsg: Serialize + serde::de::DeserializeOwned + Send + Sync + 'static {
    /// Received in place (see `Behaviour::zero_copy`).
    const ZERO_COPY: bool;
    fn new(pos: [f64; 2], payload: &Blob) -> Self;
    fn pos(&self) -> [f64; 2];
}

impl BeaconMsg for Beacon {
    const ZERO_COPY: bool = false;
    fn new(pos: [f64; 2], _payload: &Blob) -> Self {
        Beacon { pos }
    }
    fn pos(&self) -> [f64; 2] {
        self.pos
    }
}

impl BeaconMsg for BulkBeacon {
    const ZERO_COPY: bool = true;
    fn new(pos: [f64; 2], payload: &Blob) -> Self {
        BulkBeacon {
            pos,
            payload: payload.clone(),
        }
    }
    fn pos(&self) -> [f64; 2] {
        self.pos
    }
}

/// How many of the nearest robots heard repel a roaming robot: two (docs/search.md 2.3, eq. 5
/// and Fig. 2 of the search paper).
const NEAREST_HEARD: usize = 2;

/// The registry's name of this behaviour.
pub const NAME: &str = "roam";

/// The scenario sections it reads (a run refuses any other behaviour's or mission's section).
pub const SECTIONS: &[&str] = &["roam"];

/// Checks the `[roam]` section.
pub fn validate(sc: &Scenario, c: &Check) -> Result<(), ConfigError> {
    super::require_holonomic(sc, c, &sc.run.behaviour)?;
    let r = &sc.roam;
    c.range_f("roam.l_r", r.l_r, 0.0, 1e7, true)?;
    c.range_f("roam.c", r.c, 0.0, 1e7, true)?;
    c.range_f("roam.l1", r.l1, 0.0, 1e7, true)?;
    c.range_f("roam.obstacle_range", r.obstacle_range, 0.0, 1e7, false)?;
    c.range_f("roam.obstacle_weight", r.obstacle_weight, 0.0, 1e7, false)?;
    c.range_u(
        "roam.payload_bytes",
        r.payload_bytes as u64,
        0,
        sc.radio
            .max_message_bytes
            .saturating_sub(ROAM_BEACON_OVERHEAD) as u64,
    )
    .map_err(|mut e| {
        e.message += " (radio.max_message_bytes less the beacon's own bytes)";
        e
    })
}

/// Nothing to resolve: the `[roam]` section lists every value.
pub fn resolve(_sc: &mut Scenario) -> Result<(), ConfigError> {
    Ok(())
}

/// Beacons with a bulk payload are their own type (received in place).
pub fn dispatch<V: crate::BehaviourVisitor>(sc: &Scenario, v: V) -> V::Out {
    if sc.roam.payload_bytes > 0 {
        v.visit(&|i| Roam::<BulkBeacon>::new(sc, i))
    } else {
        v.visit(&|i| Roam::<Beacon>::new(sc, i))
    }
}

pub struct Roam<M = Beacon> {
    p: RoamParams,
    /// Eq. (5)'s constants (c, l_1) for the shared kernel.
    force: virtual_force::Params,
    v_max: f64,
    /// Current heading, kept while no force acts (docs/search.md 5 item 5).
    heading: f64,
    /// What each bulk beacon carries besides the position (a byte pattern of the robot's id).
    payload: Blob,
    _m: std::marker::PhantomData<M>,
}

impl<M: BeaconMsg> Roam<M> {
    pub fn new(sc: &Scenario, robot: u32) -> Roam<M> {
        let mut rng = streams::rng(sc.run.seed, robot, streams::ROAM_HEADING);
        Roam {
            p: sc.roam.clone(),
            force: virtual_force::Params {
                c: sc.roam.c,
                l1: sc.roam.l1,
                l_r: sc.roam.l_r,
                l_b: sc.roam.obstacle_range,
                v_max: sc.robot.v_max,
            },
            v_max: sc.robot.v_max,
            heading: rng.gen_range(-std::f64::consts::PI..std::f64::consts::PI),
            payload: Blob::from(vec![robot as u8; sc.roam.payload_bytes as usize]),
            _m: std::marker::PhantomData,
        }
    }

    /// Eq. (5): ||f_vr|| = c (l_1 / d)^2 for 0 < d <= d_0, directed away from the object.
    fn repulsion(&self, me: [f64; 2], other: [f64; 2], d0: f64) -> [f64; 2] {
        let (dx, dy) = (me[0] - other[0], me[1] - other[1]);
        let d = (dx * dx + dy * dy).sqrt();
        if d <= 1e-9 || d > d0 {
            return [0.0, 0.0];
        }
        let f = virtual_force::magnitude(d, d0, &self.force);
        // Direction times magnitude in this order (not the kernel's `repulsion`, which
        // divides first): roam's recordings depend on the rounding of these bits.
        [f * dx / d, f * dy / d]
    }
}

impl<M: BeaconMsg> Behaviour for Roam<M> {
    type Msg = M;

    /// Bulk beacons are received in place.
    fn zero_copy(&self) -> bool {
        M::ZERO_COPY
    }

    fn step_refs(&mut self, s: &Sense, inbox: &[&Received<M>], out: &mut Outbox<M>) -> Command {
        out.broadcast(M::new(s.pos, &self.payload));
        let me = s.pos;
        // The two nearest robots heard (positions they sent last tick); ties by sender id.
        let mut heard = Nearest::<NEAREST_HEARD>::default();
        for r in inbox {
            let pos = r.msg.pos();
            heard.offer((swarm::radio::distance(me, pos), r.from, pos));
        }
        let d0 = 2.0 * self.p.l_r;
        let mut f = [0.0, 0.0];
        for &(_, _, pos) in heard.as_slice() {
            let r = self.repulsion(me, pos, d0);
            f[0] += r[0];
            f[1] += r[1];
        }
        for &q in s.obstacle_points() {
            let r = self.repulsion(me, q, self.p.obstacle_range);
            f[0] += self.p.obstacle_weight * r[0];
            f[1] += self.p.obstacle_weight * r[1];
        }
        if f[0] != 0.0 || f[1] != 0.0 {
            self.heading = f[1].atan2(f[0]);
        }
        // V_if(t+1) = V_max (cos angle(f), sin angle(f)).
        Command {
            cmd: [
                self.v_max * self.heading.cos(),
                self.v_max * self.heading.sin(),
            ],
            events: 0,
            ..Command::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn received(from: u32, pos: [f64; 2]) -> Received<Beacon> {
        Received {
            from,
            tick: 0,
            seq: 1,
            sender_pos: pos,
            unicast: false,
            msg: Beacon { pos },
        }
    }

    #[test]
    fn a_bulk_payload_rides_on_every_beacon_and_asks_for_zero_copy_receive() {
        let mut sc = Scenario::roam();
        assert!(
            !Roam::<Beacon>::new(&sc, 3).zero_copy(),
            "position-only beacons decode as usual"
        );
        sc.radio.max_message_bytes = 4096;
        sc.roam.payload_bytes = 3000;
        sc.validate(&|k| k.to_string()).unwrap();
        let mut r = Roam::<BulkBeacon>::new(&sc, 3);
        assert!(r.zero_copy());
        let mut out = Outbox::new_for_tests(4);
        let s = Sense::zeroed();
        r.step(&s, &[], &mut out);
        let sent = out.queued();
        assert_eq!(sent.len(), 1);
        assert_eq!(&sent[0].1.payload[..], &[3u8; 3000][..]);
        // It must fit in a radio message.
        sc.roam.payload_bytes = 4090;
        let e = validate(
            &sc,
            &Check {
                key_source: &|k| k.to_string(),
            },
        )
        .unwrap_err();
        assert!(e.to_string().contains("roam.payload_bytes"), "{e}");
    }

    #[test]
    fn moves_away_from_the_two_nearest_heard_robots_at_full_speed() {
        let sc = Scenario::roam();
        let mut r = Roam::<Beacon>::new(&sc, 0);
        let mut s = Sense::zeroed();
        s.pos = [500.0, 500.0];
        let inbox = vec![
            received(1, [490.0, 500.0]),
            received(2, [500.0, 490.0]),
            received(3, [560.0, 560.0]),
        ];
        let mut out = Outbox::new_for_tests(4);
        let c = r.step(&s, &inbox, &mut out);
        let speed = (c.cmd[0].powi(2) + c.cmd[1].powi(2)).sqrt();
        assert!((speed - 10.0).abs() < 1e-9);
        // Away from (490,500) and (500,490): up and to the right, at 45 degrees.
        assert!(
            (c.cmd[0] - c.cmd[1]).abs() < 1e-9 && c.cmd[0] > 0.0,
            "{:?}",
            c.cmd
        );
    }

    #[test]
    fn keeps_heading_when_nothing_is_heard() {
        let sc = Scenario::roam();
        let mut r = Roam::<Beacon>::new(&sc, 4);
        let mut s = Sense::zeroed();
        s.pos = [500.0, 500.0];
        let a = r.step(&s, &[], &mut Outbox::new_for_tests(4));
        let b = r.step(&s, &[], &mut Outbox::new_for_tests(4));
        assert_eq!(a, b);
    }
}
