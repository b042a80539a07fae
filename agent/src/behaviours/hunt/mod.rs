//! The hunting behaviour of thesis 003 chapters 2-3 (docs/hunting.md; kernels in
//! `crate::hunt`): one agent per robot (`robot.rs`: the Bidder over the radio, the APF pursuit
//! on a unicycle, hunting points, re-planning as the auctioneer sends it) and the auctioneer
//! as an agent of its own (`auctioneer.rs`: the station, the last agent of the run, with no
//! body). Both speak `messages::HuntMsg` through the behaviour API only.

pub mod auctioneer;
pub mod messages;
pub mod robot;

pub use messages::HuntMsg;

use swarm::scenario::{Check, ConfigError, Scenario};
use swarm::{Behaviour, Command, Outbox, Received, Sense};

/// The registry's name of this behaviour.
pub const NAME: &str = "hunt";

/// The scenario sections it reads (a run refuses any other behaviour's or mission's section).
pub const SECTIONS: &[&str] = &["hunt"];

/// Nothing of its own to check: the behaviour reads only the `[hunt]` section, which the
/// world's hunt mission (implied by this behaviour) validates: rows, agent count, kinematics,
/// limits.
pub fn validate(_sc: &Scenario, _c: &Check) -> Result<(), ConfigError> {
    Ok(())
}

/// Nothing to resolve: `[hunt.params]` is written in full by the scenario itself.
pub fn resolve(_sc: &mut Scenario) -> Result<(), ConfigError> {
    Ok(())
}

/// Calls `v` with the constructor: robots for agents 0..bodies, the auctioneer for the station.
pub fn dispatch<V: crate::BehaviourVisitor>(sc: &Scenario, v: V) -> V::Out {
    v.visit(&|i| Hunt::new(sc, i))
}

/// A hunting agent: a robot or the auctioneer.
#[allow(clippy::large_enum_variant)]
pub enum Hunt {
    Robot(robot::HuntRobot),
    Auctioneer(auctioneer::Station),
}

impl Hunt {
    pub fn new(sc: &Scenario, i: u32) -> Hunt {
        if sc.is_station(i) {
            Hunt::Auctioneer(auctioneer::Station::new(sc))
        } else {
            Hunt::Robot(robot::HuntRobot::new(sc, i))
        }
    }
}

impl Behaviour for Hunt {
    type Msg = HuntMsg;
    fn step_refs(
        &mut self,
        sense: &Sense,
        inbox: &[&Received<HuntMsg>],
        out: &mut Outbox<HuntMsg>,
    ) -> Command {
        match self {
            Hunt::Robot(r) => r.step(sense, inbox, out),
            Hunt::Auctioneer(a) => a.step(sense, inbox, out),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use swarm::frames::{Entity, RadioHeader, ENTITY_HAS_POS};
    use swarm::sections::hunt::ENTITY_EVADER;

    fn example() -> Scenario {
        Scenario::parse(
            include_str!("../../../../configs/hunt-example-3a.toml"),
            "hunt-example-3a.toml",
        )
        .unwrap()
    }

    fn sense(tick: u64, robot: u32, pos: [f64; 2], heading: f64) -> Box<Sense> {
        let mut s = Sense::zeroed();
        s.tick = tick;
        s.robot = robot;
        s.pos = pos;
        s.heading = heading;
        s
    }

    fn from(sender: u32, msg: HuntMsg) -> Received<HuntMsg> {
        let h = RadioHeader {
            sender,
            sender_pos: [5.0, 5.0],
            ..Default::default()
        };
        Received::new(&h, msg)
    }

    #[test]
    fn the_auctioneer_opens_with_the_four_tasks_present_and_a_robot_bids_its_best() {
        let sc = example();
        let mut station = Hunt::new(&sc, 15);
        assert!(matches!(station, Hunt::Auctioneer(_)));
        let mut out = Outbox::new_for_tests(16);
        let c = station.step(&sense(0, 15, [5.0, 5.0], 0.0), &[], &mut out);
        assert_eq!(c.cmd, [0.0, 0.0]);
        let HuntMsg::Announce { auction, a, .. } = out.queued()[0].1.clone() else {
            panic!("{:?}", out.queued());
        };
        let ids: Vec<u32> = a.tasks.iter().map(|t| t.id).collect();
        assert_eq!(ids, vec![1, 2, 3, 4], "T5 appears later");
        // alpha z_max = 0.8 x Table 3.1's caps.
        assert_eq!(a.tasks[0].reward, 0.8 * 520.0);
        // R1 (agent 0) answers with a bid unicast to the station, for its own best task.
        let mut r1 = Hunt::new(&sc, 0);
        let mut out = Outbox::new_for_tests(16);
        let msg = HuntMsg::Announce {
            auction,
            replan_of: vec![],
            a: a.clone(),
        };
        r1.step(&sense(1, 0, [1.54, 6.88], 0.0), &[from(15, msg)], &mut out);
        let bids: Vec<_> = out
            .queued()
            .iter()
            .filter_map(|(to, m)| match m {
                HuntMsg::Bid { bid, .. } => Some((*to, bid.clone())),
                _ => None,
            })
            .collect();
        assert_eq!(bids.len(), 1);
        assert_eq!(bids[0].0, 15);
        let robot = crate::hunt::scenario::robot_of(&sc.hunt().robots[0]);
        let best = crate::hunt::auction::Bidder::new(robot, &sc.hunt().params).best_task(&a);
        assert_eq!(Some((bids[0].1.task, bids[0].1.utility)), best);
    }

    #[test]
    fn an_assigned_robot_chases_its_target_within_its_own_limits() {
        let sc = example();
        let mut r1 = Hunt::new(&sc, 0);
        let assign = HuntMsg::Assign {
            epoch: 1,
            task: 1,
            members: vec![1, 2, 15],
            reward: 480.0,
        };
        let mut s = sense(5, 0, [1.54, 6.88], 0.0);
        // T1 at (1.94, 9.11): north-north-east of R1, 2.26 km away.
        s.entities[0] = Entity {
            id: 1,
            kind: ENTITY_EVADER,
            flags: ENTITY_HAS_POS,
            reserved: 0,
            pos: [1.94, 9.11],
            value: 0.0,
        };
        s.n_entities = 1;
        let mut out = Outbox::new_for_tests(16);
        let c = r1.step(&s, &[from(15, assign)], &mut out);
        let dt = sc.hunt().params.minutes_per_tick;
        let (v_max, w_max) = (0.8 * dt, 6.0 * dt);
        // Heading 0 (east) while the target lies at about 80 degrees: it turns left at its
        // full turn rate; cos(80 deg) > 0, so it also moves, below its own speed.
        assert!((c.cmd[1] - w_max).abs() < 1e-12, "{:?}", c.cmd);
        assert!(c.cmd[0] > 0.0 && c.cmd[0] <= v_max, "{:?}", c.cmd);
        assert_eq!(c.events, 1, "display state = its task");
        assert_eq!(c.report[0], 1.0);
        assert!(c.report[1].is_nan(), "no hunting point yet");
    }
}
