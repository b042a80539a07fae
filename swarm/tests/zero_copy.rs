//! Zero-copy radio receive over real iceoryx2 shared memory (one process, a real radio
//! service): a `Blob` field of a delivered message is a view into the received sample, the
//! sample goes back to its publisher when the last view is dropped, and past the per-link hold
//! limit messages arrive as copies with the same content.

use serde::{Deserialize, Serialize};
use std::cell::RefCell;
use std::rc::Rc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use swarm::transport::{self, ShmTx};
use swarm::{cleanup, AgentRuntime, Behaviour, Blob, Command, Outbox, Received, Scenario, Sense};

#[derive(Clone, Serialize, Deserialize)]
struct Image {
    frame: u32,
    data: Blob,
}

/// Sends `frame` (when set) as an image; keeps what it receives in `got`.
struct Camera {
    frame: Rc<RefCell<Option<u32>>>,
    got: Rc<RefCell<Vec<Image>>>,
}

fn pixels(frame: u32) -> Vec<u8> {
    (0..8192u32).map(|i| (i * 7 + frame) as u8).collect()
}

impl Behaviour for Camera {
    type Msg = Image;
    fn zero_copy(&self) -> bool {
        true
    }
    fn step_refs(
        &mut self,
        _s: &Sense,
        inbox: &[&Received<Image>],
        out: &mut Outbox<Image>,
    ) -> Command {
        self.got
            .borrow_mut()
            .extend(inbox.iter().map(|r| r.msg.clone()));
        if let Some(f) = self.frame.borrow_mut().take() {
            out.broadcast(Image {
                frame: f,
                data: Blob::from(pixels(f)),
            });
        }
        Command::default()
    }
}

fn sense(robot: u32, other: u32, tick: u64, x: f64) -> Box<Sense> {
    let mut s = Sense::zeroed();
    s.robot = robot;
    s.tick = tick;
    s.pos = [x, 0.0];
    s.alive_robots = 2;
    s.neighbours[0] = other;
    s.n_neighbours = 1;
    s
}

#[test]
fn blob_fields_are_views_into_the_received_sample() {
    transport::quiet_logs();
    let prefix = format!("swzc{}_", std::process::id());
    // Removes the run's files however the test ends (a failed assertion unwinds through it).
    struct Cleanup<'a>(&'a str);
    impl Drop for Cleanup<'_> {
        fn drop(&mut self) {
            cleanup::remove_run(self.0);
        }
    }
    let _cleanup = Cleanup(&prefix);
    let mut sc = Scenario::roam();
    sc.run.robots = 2;
    sc.radio.max_message_bytes = 16 * 1024;
    sc.radio.max_messages_per_tick = 1;
    sc.radio.loss = 0.0;
    sc.radio.zero_copy_held = 1;
    {
        let config = transport::run_config(&prefix).unwrap();
        let node = transport::node(&config, "zc").unwrap();
        let svc = transport::radio_service(&node, 0, &sc, true).unwrap();
        let publisher = transport::radio_publisher(&svc, &sc).unwrap();
        let sub = svc
            .subscriber_builder()
            .buffer_size(transport::radio_buffer(&sc))
            .create()
            .unwrap();
        let mut tx = ShmTx {
            publisher: &publisher,
            failures: 0,
        };
        let frame = Rc::new(RefCell::new(None));
        let got = Rc::new(RefCell::new(Vec::new()));
        let mut cam = AgentRuntime::new(
            &sc,
            0,
            Camera {
                frame: frame.clone(),
                got: Rc::new(RefCell::new(Vec::new())),
            },
        );
        let mut rx = AgentRuntime::new(
            &sc,
            1,
            Camera {
                frame: Rc::new(RefCell::new(None)),
                got: got.clone(),
            },
        );
        let live = Arc::new(AtomicUsize::new(0));
        let held = transport::radio_held_per_link(&sc);
        assert_eq!(held, 1);
        // Tick 0: robot 1 links to robot 0. Then each odd tick robot 0 sends a frame, and the
        // next tick robot 1 takes it off the link and steps.
        for (rt, s) in [
            (&mut cam, sense(0, 1, 0, 0.0)),
            (&mut rx, sense(1, 0, 0, 10.0)),
        ] {
            rt.begin(&s);
            rt.update_links(&s);
        }
        let mut round = |f: u32, t: u64| {
            *frame.borrow_mut() = Some(f);
            let s0 = sense(0, 1, t, 0.0);
            cam.begin(&s0);
            rx.begin(&sense(1, 0, t, 10.0));
            assert_eq!(cam.step(&s0, &mut tx).n_sent, 1);
            let s1 = sense(1, 0, t + 1, 10.0);
            rx.begin(&s1);
            let m = sub.receive().unwrap().expect("the frame is on the link");
            let in_shm = m.payload().as_ptr_range();
            transport::take_radio(&mut rx, m, &live, held);
            assert_eq!(rx.step(&s1, &mut tx).radio_delivered, 1);
            in_shm
        };

        let in_shm = round(1, 1);
        {
            let g = got.borrow();
            let img = &g[0];
            assert_eq!(img.frame, 1);
            assert_eq!(&img.data[..], &pixels(1)[..]);
            assert!(img.data.is_view(), "received in place");
            assert!(
                in_shm.contains(&img.data.as_ptr()),
                "the view points into the iceoryx2 sample"
            );
        }
        assert_eq!(live.load(Ordering::Acquire), 1, "the view holds its sample");

        // The link's hold limit (one tick's messages) is reached while frame 1 is kept: the
        // next frame arrives as a copy, with the same content a view would have.
        round(2, 3);
        {
            let g = got.borrow();
            assert_eq!(&g[1].data[..], &pixels(2)[..]);
            assert!(!g[1].data.is_view(), "past the hold limit: a copy");
        }
        assert_eq!(live.load(Ordering::Acquire), 1);

        // Dropping the views returns the samples: the next frame is a view again.
        got.borrow_mut().clear();
        assert_eq!(live.load(Ordering::Acquire), 0, "sample returned");
        round(3, 5);
        assert!(got.borrow()[0].data.is_view());
        got.borrow_mut().clear();
        assert_eq!(live.load(Ordering::Acquire), 0);
        assert_eq!(tx.failures, 0);
    }
    cleanup::remove_run(&prefix);
    assert!(
        cleanup::shm_files(&prefix).is_empty(),
        "nothing of the test left in /dev/shm"
    );
}
