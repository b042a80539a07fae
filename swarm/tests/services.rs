//! The generic service builder against real iceoryx2: a service is created with the
//! capacities asked for, an agent opens it as created, and a failure names the service.

use iceoryx2::service::port_factory::PortFactory as _;
use swarm::scenario::Scenario;
use swarm::transport::{self, PubSubCapacity, Reach, ServiceId, TransportError};
use swarm::{cleanup, Sense};

/// Removes the test's files however it ends.
struct Cleanup(String);
impl Drop for Cleanup {
    fn drop(&mut self) {
        cleanup::remove_run(&self.0);
    }
}

#[test]
fn services_have_their_capacities_and_errors_name_them() {
    transport::quiet_logs();
    let prefix = format!("swsv{}_", std::process::id());
    let _cleanup = Cleanup(prefix.clone());
    let mut sc = Scenario::roam();
    sc.run.robots = 7;
    sc.radio.max_messages_per_tick = 3;
    sc.radio.zero_copy_held = 2;
    {
        let config = transport::run_config(&prefix).unwrap();
        let world = transport::node(&config, "world").unwrap();
        let agent = transport::node(&config, "agent-2").unwrap();

        // Opening before the world created it: the error names robot 2's act service.
        let e = transport::act_service(&agent, 2, false).unwrap_err();
        assert!(matches!(e, TransportError::Open { .. }), "{e}");
        assert_eq!(e.robot(), Some(2));
        assert_eq!(e.service(), Some(&ServiceId::Act(2)));
        assert!(
            e.to_string().starts_with("open service robot/2/act: "),
            "{e}"
        );
        let e = transport::air_service(&agent, &sc, 0, false).unwrap_err();
        assert_eq!(e.service(), Some(&ServiceId::Air { generation: 0 }));
        assert_eq!(e.robot(), None);

        let air = transport::air_service(&world, &sc, 0, true).unwrap();
        let c = air.static_config();
        // Every agent subscribes, plus two restarted agents' dead predecessors.
        assert_eq!(c.max_subscribers(), 7 + 2);
        assert_eq!(c.max_publishers(), 1);
        assert_eq!(c.max_nodes(), 7 + 2 + 2);
        assert_eq!(c.subscriber_max_buffer_size(), 1);
        // The sample being read and the two zero-copy views may hold.
        assert_eq!(c.subscriber_max_borrowed_samples(), 3);
        assert_eq!(c.history_size(), 0);
        let opened = transport::air_service(&agent, &sc, 0, false).unwrap();
        assert_eq!(opened.static_config().max_subscribers(), 9);
        let act = transport::act_service(&world, 2, true).unwrap();
        assert_eq!(act.static_config().subscriber_max_buffer_size(), 2);

        // Creating it twice fails, naming it.
        let e = transport::act_service(&world, 2, true).unwrap_err();
        assert!(matches!(e, TransportError::Create { .. }), "{e}");
        assert_eq!(e.robot(), Some(2));

        let control = transport::control_service(&world, true).unwrap();
        assert!(!control.static_config().has_safe_overflow());
        assert_eq!(control.static_config().subscriber_max_buffer_size(), 256);

        // Any payload through the same builder: a fixed-size frame under a name of our own.
        let cap = PubSubCapacity {
            publishers: 3,
            subscribers: 5,
            nodes: 9,
            buffer: 4,
            borrowed: None,
            history: Some(1),
            safe_overflow: Some(true),
        };
        let own = ServiceId::from("test/frames");
        let svc = transport::pub_sub::<Sense, ()>(&world, own.clone(), Reach::Create(cap)).unwrap();
        let c = svc.static_config();
        assert_eq!(
            (c.max_publishers(), c.max_subscribers(), c.max_nodes()),
            (3, 5, 9)
        );
        assert_eq!((c.subscriber_max_buffer_size(), c.history_size()), (4, 1));
        assert!(c.has_safe_overflow());
        assert_eq!(ServiceId::of(&svc), own);
        transport::pub_sub::<Sense, ()>(&agent, own, Reach::Open).unwrap();
    }
}
