//! Zero-copy radio receive over real iceoryx2 shared memory (one process, the real air
//! service): a `Blob` field of a delivered message is a view into the received air sample, the
//! sample goes back to the world when the last view is dropped, and past the hold limit
//! (`radio.zero_copy_held`) messages arrive as copies with the same content.

use serde::{Deserialize, Serialize};
use std::cell::RefCell;
use std::rc::Rc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use swarm::air::{write_air, TickAir};
use swarm::mailbox::Air;
use swarm::transport;
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

fn sense(robot: u32, tick: u64, x: f64) -> Box<Sense> {
    let mut s = Sense::zeroed();
    s.robot = robot;
    s.tick = tick;
    s.pos = [x, 0.0];
    s.alive_robots = 2;
    s
}

/// The air of `sent` (robot 0's messages) with robot 1 hearing all of them.
fn air_of(sent: &Air, tick: u64) -> TickAir {
    let mut a = TickAir {
        tick,
        ..Default::default()
    };
    for (h, p) in sent.messages() {
        let at = a.bytes.len();
        a.bytes.extend_from_slice(p);
        a.messages.push((*h, at..at + p.len()));
    }
    a.start = vec![0, 0, a.messages.len() as u32];
    a.index = (0..a.messages.len() as u32).collect();
    a
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
        let svc = transport::air_service(&node, &sc, 0, true).unwrap();
        let publisher = transport::air_publisher(&svc, &sc).unwrap();
        let sub = svc.subscriber_builder().buffer_size(1).create().unwrap();
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
        let held = transport::air_held(&sc);
        assert_eq!(held, 1);
        // Each odd tick robot 0 sends a frame; the world publishes it in the air of the next
        // tick, where robot 1 reads it in place and steps.
        let mut round = |f: u32, t: u64| {
            *frame.borrow_mut() = Some(f);
            let mut sent = Air::default();
            assert_eq!(
                cam.step_owned(&sense(0, t, 0.0), &[], 0, &mut sent).n_sent,
                1
            );
            let air = air_of(&sent, t);
            let len = swarm::air::air_len(Some(&air), 2);
            let sample = publisher.loan_slice_uninit(len).unwrap();
            // SAFETY: shared memory is always initialised bytes; write_air writes them all.
            let mut sample = unsafe { sample.assume_init() };
            let h = write_air(Some(&air), 2, t + 1, sample.payload_mut());
            *sample.user_header_mut() = h;
            sample.send().unwrap();
            let m = sub.receive().unwrap().expect("the air is there");
            let in_shm = m.payload().as_ptr_range();
            let mut inbox = Vec::new();
            let bad = transport::air_inbox(m, 1, rx.zero_copy(), &live, held, &mut inbox);
            let a = rx.step_owned(&sense(1, t + 1, 10.0), &inbox, bad, &mut Air::default());
            assert_eq!((a.radio_delivered, a.radio_malformed), (1, 0));
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

        // The hold limit (one air sample) is reached while frame 1 is kept: the next frames
        // arrive as copies, with the same content a view would have; ten airs go by while
        // frame 1 is held and its bytes stay (the static slot it lies in is not reused
        // while held).
        for k in 0..10u32 {
            round(2 + k, 3 + 2 * k as u64);
        }
        {
            let g = got.borrow();
            assert_eq!(&g[0].data[..], &pixels(1)[..], "the held view's bytes stay");
            assert_eq!(&g[1].data[..], &pixels(2)[..]);
            assert!(!g[1].data.is_view(), "past the hold limit: a copy");
            assert_eq!(&g[10].data[..], &pixels(11)[..]);
        }
        assert_eq!(live.load(Ordering::Acquire), 1);

        // Dropping the views returns the samples: the next frame is a view again.
        got.borrow_mut().clear();
        assert_eq!(live.load(Ordering::Acquire), 0, "sample returned");
        round(3, 5);
        assert!(got.borrow()[0].data.is_view());
        got.borrow_mut().clear();
        assert_eq!(live.load(Ordering::Acquire), 0);
    }
    cleanup::remove_run(&prefix);
    assert!(
        cleanup::shm_files(&prefix).is_empty(),
        "nothing of the test left in /dev/shm"
    );
}
