//! iceoryx2 plumbing of the multi-process executor: per-run configuration, service names and
//! capacities.
//!
//! Every service is created by the world, with the capacities the run needs, before any agent
//! starts; agents only open them. Each run has its own iceoryx2 prefix and root folder, so two
//! runs never see each other and a run's leftovers are easy to find and remove.

use crate::air::AirView;
use crate::blob::AsBytes;
use crate::frames::{Action, AirHeader, Control, Sense, SenseHeader, WorldStatus};
use crate::scenario::Scenario;
use crate::wire::{decode, decode_in, Received};
use iceoryx2::prelude::*;
use serde::de::DeserializeOwned;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

mod act_board;
mod act_sink;
mod acts;
mod air_source;
mod error;
mod sense_source;
mod service;
pub use act_board::{
    chunks as act_board_chunks, ActChunk, ActHead, BoardSink, BoardSource, CHUNK_AREA, HEAD_AREA,
};
pub use act_sink::{attach_of, PubSubSink, PubSubSource, ATTACH_NOTICE};
pub use acts::{ActSink, ActSource};
pub use air_source::{AirGot, AirSink, AirSource};
pub use error::{Port, TransportError, TransportResult};
pub use sense_source::{SenseSink, SenseSource};
pub use service::{
    event, pub_sub, service_name, EventCapacity, EventService, Generation, PubSubCapacity,
    PubSubService, Reach, ServiceId, ShmPayload, AIR_NAME, CONTROL_NAME, SENSES_NAME, STATUS_NAME,
};

/// A boxed error of any kind, and a result with it: what a process's run loop returns when
/// it mixes transport, file and scenario errors (the world process does). The functions here
/// return the typed [`TransportError`], which converts into it with `?`.
pub type Error = Box<dyn std::error::Error + Send + Sync>;
pub type Result<T> = std::result::Result<T, Error>;

/// One robot's Sense frame as one sample (`robot/<i>/sense`): the latency benchmark's
/// one-hop frame.
pub type SenseService = PubSubService<Sense, ()>;
/// Every robot's Sense record of a tick, packed (`crate::sense_pack`), in one sample.
pub type SensesService = PubSubService<[u8], SenseHeader>;
/// A robot's Action frame as the user header, its messages of the tick behind it.
pub type ActService = PubSubService<[u8], Action>;
/// The world's one publication a tick of the messages due (`swarm::air`).
pub type AirService = PubSubService<[u8], AirHeader>;
pub type StatusService = PubSubService<WorldStatus, ()>;
pub type ControlService = PubSubService<Control, ()>;

/// Where iceoryx2 keeps a run's node and service folders: on tmpfs, in a folder named with the
/// run's prefix (`/dev/shm/<prefix>iox2/`). On this VM /tmp is ext4, where creating iceoryx2's
/// many small tag files cost ~50 ms per radio link at start-up (ext4 inode allocation); on tmpfs
/// it is negligible. Everything of a run is then `/dev/shm/<prefix>*`.
pub const IOX2_ROOT: &str = "/dev/shm";

/// The per-run iceoryx2 file prefix: short, unique per run id.
pub fn prefix_for(run_id: &str) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in run_id.bytes() {
        h ^= b as u64;
        h = h.wrapping_mul(0x100_0000_01b3);
    }
    format!("sw{:010x}_", h & 0xff_ffff_ffff)
}

pub fn root_for(prefix: &str) -> PathBuf {
    PathBuf::from(IOX2_ROOT).join(format!("{prefix}iox2"))
}

/// The iceoryx2 configuration of one run.
/// Expired publisher connections a subscriber keeps readable (see `run_config`).
pub const EXPIRED_CONNECTIONS: usize = 4;

pub fn run_config(prefix: &str) -> TransportResult<Config> {
    let mut c = Config::default();
    c.global.prefix =
        FileName::new(prefix.as_bytes()).map_err(|source| TransportError::Prefix {
            prefix: prefix.to_string(),
            source,
        })?;
    let root = root_for(prefix);
    let mut root_s = root.display().to_string();
    root_s.push('/');
    let root_path = Path::new(root_s.as_bytes()).map_err(|source| TransportError::RootPath {
        path: root_s.clone(),
        source,
    })?;
    c.global.set_root_path(&root_path);
    // Implicit dead-node cleanup scans every node of the run on each service open: with N
    // agents opening ~N links each that is O(N^2) node checks at start-up (8 s for 50 robots
    // on this VM). The world cleans dead nodes explicitly when a robot dies instead.
    c.global.service.cleanup_dead_nodes_on_open = false;
    c.global.node.cleanup_dead_nodes_on_creation = false;
    c.global.node.cleanup_dead_nodes_on_destruction = false;
    // Each subscriber preallocates room for this many expired connections (a publisher that
    // left with samples unread) next to its live ones: iceoryx2's default of 128 costs ~464 KiB
    // of private heap per subscriber, i.e. per radio link (measured in /proc/PID/smaps). A radio
    // service has at most 1 + RESTART_SLACK publishers, so a few slots are plenty.
    c.defaults
        .publish_subscribe
        .subscriber_expired_connection_buffer = EXPIRED_CONNECTIONS;
    Ok(c)
}

/// A node of this run. Signal handling is left to our own code.
pub fn node(config: &Config, name: &str) -> TransportResult<Node<ipc::Service>> {
    let node_name = NodeName::new(name).map_err(|source| TransportError::NodeName {
        name: name.to_string(),
        source,
    })?;
    NodeBuilder::new()
        .config(config)
        .name(&node_name)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .map_err(|source| TransportError::Node {
            name: name.to_string(),
            source,
        })
}

/// Slack for a restarted agent whose dead predecessor's ports are not cleaned yet.
const RESTART_SLACK: usize = 1;

/// Sense frames: the world publishes, the robot's agent subscribes; the latest frame only.
pub fn sense_capacity() -> PubSubCapacity {
    PubSubCapacity {
        publishers: 1 + RESTART_SLACK,
        subscribers: 1 + RESTART_SLACK,
        nodes: 2 + 2 * RESTART_SLACK,
        buffer: 1,
        borrowed: None,
        history: Some(0),
        safe_overflow: None,
    }
}

/// Act samples the world's subscriber of a robot's act service buffers: this tick's action
/// and one late one (real-time mode), or the attach notice and the first action of a
/// replacement.
const ACT_BUFFER: usize = 2;

/// Action frames with the tick's messages: the robot's agent publishes (a restarted agent's
/// dead predecessor may still hold its port until it is cleaned), the world subscribes.
/// Tighter capacities (one subscriber, 3 nodes) were tried: they moved the agent's cost of a
/// send by ~2 % of its instructions and the run's /dev/shm not at all (every file of a
/// service takes one 4 KiB page either way), and two runs under a load of 50-90 had an agent
/// fail before it attached, which was never seen with these; so these stay.
pub fn act_capacity() -> PubSubCapacity {
    PubSubCapacity {
        buffer: ACT_BUFFER,
        ..sense_capacity()
    }
}

/// Bytes of an act sample's message area: the most messages a robot may send a tick, each
/// of the largest size (`swarm::air::act_bytes`).
pub fn act_slice_len(sc: &Scenario) -> usize {
    crate::air::act_bytes(sc.radio.max_messages_per_tick, sc.radio.max_message_bytes).max(8)
}

/// Air samples an agent may hold while zero-copy views refer into them
/// (`radio.zero_copy_held`); past it messages are decoded as copies, with the same content.
pub fn air_held(sc: &Scenario) -> usize {
    sc.radio.zero_copy_held as usize
}

/// The air: the world publishes once a tick, every agent subscribes (and a restarted one's
/// dead predecessor may still hold its port). Each subscriber keeps the latest sample only;
/// iceoryx2 sizes the data segment for subscribers x (buffer + borrowed) samples, so the
/// borrowed ones are the one being read and those zero-copy views hold.
pub fn air_capacity(sc: &Scenario) -> PubSubCapacity {
    let subscribers = sc.run.robots as usize + 2 * RESTART_SLACK;
    PubSubCapacity {
        publishers: 1,
        subscribers,
        nodes: subscribers + 2,
        buffer: 1,
        borrowed: Some(air_held(sc) + 1),
        history: Some(0),
        safe_overflow: None,
    }
}

/// Bytes of the largest air a tick of this scenario can make: every agent sends
/// `radio.max_messages_per_tick` messages of `radio.max_message_bytes`, each reaching every
/// agent (`swarm::air::air_max_len`). The air's slots are this size
/// (`AllocationStrategy::Static`): iceoryx2 neither zeroes nor touches a slot's pages, so
/// only the bytes of real airs are ever backed by memory.
pub fn air_max_len(sc: &Scenario) -> usize {
    crate::air::air_max_len(
        sc.run.robots as usize,
        sc.radio.max_messages_per_tick as usize,
        sc.radio.max_message_bytes as usize,
    )
}

/// The Sense service: the world publishes every robot's record once a tick, every agent
/// subscribes (a restarted agent's dead predecessor may still hold its port). Each subscriber
/// keeps the latest sample only and holds one at a time (it copies its record out at once).
pub fn senses_capacity(sc: &Scenario) -> PubSubCapacity {
    let subscribers = sc.run.robots as usize + 2 * RESTART_SLACK;
    PubSubCapacity {
        publishers: 1,
        subscribers,
        nodes: subscribers + 2,
        buffer: 1,
        borrowed: Some(1),
        history: Some(0),
        safe_overflow: None,
    }
}

/// Bytes of the largest Sense sample of this scenario: every robot's record with every list
/// full (`crate::sense_pack::max_len`); the slots are this size, as the air's.
pub fn senses_max_len(sc: &Scenario) -> usize {
    crate::sense_pack::max_len(sc.run.robots)
}

/// The world's status: the world publishes; the orchestrator and tools subscribe.
pub fn status_capacity() -> PubSubCapacity {
    PubSubCapacity {
        publishers: 1,
        subscribers: 4,
        nodes: 6,
        buffer: 1,
        borrowed: None,
        history: None,
        safe_overflow: None,
    }
}

/// The control channel: the orchestrator (and tools) publish, the world subscribes. Nothing
/// is dropped: a full buffer fails the send instead.
pub fn control_capacity() -> PubSubCapacity {
    PubSubCapacity {
        publishers: 4,
        subscribers: 1,
        nodes: 6,
        buffer: 256,
        borrowed: None,
        history: None,
        safe_overflow: Some(false),
    }
}

/// The run's Sense service: the world creates it (`create`), agents open it.
pub fn senses_service(
    node: &Node<ipc::Service>,
    sc: &Scenario,
    generation: Generation,
    create: bool,
) -> TransportResult<SensesService> {
    pub_sub(
        node,
        ServiceId::Senses { generation },
        Reach::create_if(create, || senses_capacity(sc)),
    )
}

/// A publisher of `[u8]` samples with user header `H` and static slots of `slot` bytes, one
/// loan at a time: the shape of every per-tick publisher of the run (Sense, air, act).
fn static_publisher<H: std::fmt::Debug + ZeroCopySend>(
    svc: &PubSubService<[u8], H>,
    slot: usize,
) -> TransportResult<iceoryx2::port::publisher::Publisher<ipc::Service, [u8], H>> {
    svc.publisher_builder()
        .initial_max_slice_len(slot)
        .allocation_strategy(AllocationStrategy::Static)
        .max_loaned_samples(1)
        .create()
        .map_err(|source| TransportError::Publisher {
            service: ServiceId::of(svc),
            source,
        })
}

/// The world's Sense publisher: static slots of the largest Sense sample.
pub fn senses_publisher(
    svc: &SensesService,
    sc: &Scenario,
) -> TransportResult<iceoryx2::port::publisher::Publisher<ipc::Service, [u8], SenseHeader>> {
    static_publisher(svc, senses_max_len(sc))
}

/// One robot's Sense service (the latency benchmark's one-hop frame): the parent creates it
/// (`create`), the child opens it.
pub fn sense_service(
    node: &Node<ipc::Service>,
    robot: u32,
    create: bool,
) -> TransportResult<SenseService> {
    pub_sub(
        node,
        ServiceId::Sense(robot),
        Reach::create_if(create, sense_capacity),
    )
}

/// Robot i's Action service: the world creates it (`create`), the agent opens it.
pub fn act_service(
    node: &Node<ipc::Service>,
    robot: u32,
    create: bool,
) -> TransportResult<ActService> {
    pub_sub(
        node,
        ServiceId::Act(robot),
        Reach::create_if(create, act_capacity),
    )
}

/// The air service: the world creates it (`create`), agents open it.
pub fn air_service(
    node: &Node<ipc::Service>,
    sc: &Scenario,
    generation: Generation,
    create: bool,
) -> TransportResult<AirService> {
    pub_sub(
        node,
        ServiceId::Air { generation },
        Reach::create_if(create, || air_capacity(sc)),
    )
}

/// The world's status service: the world creates it (`create`), the orchestrator opens it.
pub fn status_service(node: &Node<ipc::Service>, create: bool) -> TransportResult<StatusService> {
    pub_sub(
        node,
        ServiceId::Status,
        Reach::create_if(create, status_capacity),
    )
}

/// The control service: the world creates it (`create`), the orchestrator opens it.
pub fn control_service(node: &Node<ipc::Service>, create: bool) -> TransportResult<ControlService> {
    pub_sub(
        node,
        ServiceId::Control,
        Reach::create_if(create, control_capacity),
    )
}

/// Robot i's act publisher: fixed-size slots of the largest message area (no reallocation).
pub fn act_publisher(
    svc: &ActService,
    sc: &Scenario,
) -> TransportResult<iceoryx2::port::publisher::Publisher<ipc::Service, [u8], Action>> {
    static_publisher(svc, act_slice_len(sc))
}

/// The world's subscriber of robot i's act service: this tick's sample and the next's
/// (real-time mode: one late).
pub fn act_subscriber(
    svc: &ActService,
) -> TransportResult<iceoryx2::port::subscriber::Subscriber<ipc::Service, [u8], Action>> {
    svc.subscriber_builder()
        .buffer_size(ACT_BUFFER)
        .create()
        .map_err(|source| TransportError::Subscriber {
            service: ServiceId::of(svc),
            source,
        })
}

/// The world's air publisher: static slots of the scenario's largest air
/// ([`air_max_len`]). Not `PowerOfTwo` or `BestFit`: with a growing strategy every
/// publisher-subscriber connection keeps a flag per chunk for each of up to 255 segments and
/// writes them all when it is made (~500 KiB a subscriber: 544 MiB of /dev/shm at 1,000
/// robots, which was once blamed on the samples).
pub fn air_publisher(
    svc: &AirService,
    sc: &Scenario,
) -> TransportResult<iceoryx2::port::publisher::Publisher<ipc::Service, [u8], AirHeader>> {
    static_publisher(svc, air_max_len(sc))
}

/// A sample of the air.
pub type AirSample = iceoryx2::sample::Sample<ipc::Service, [u8], AirHeader>;

/// An air sample kept while [`crate::Blob`] views refer into it (zero-copy receive). Dropping
/// the last view returns the sample to the world.
pub struct HeldSample {
    sample: std::mem::ManuallyDrop<AirSample>,
    bytes: *const u8,
    len: usize,
    thread: std::thread::ThreadId,
    live: Arc<AtomicUsize>,
}

// SAFETY: an iceoryx2 ipc sample is neither Send nor Sync because releasing it touches its
// subscriber's single-threaded state (an Rc). HeldSample reads only the payload bytes through
// the pointer taken on the receiving thread (shared memory that the publisher does not reuse
// while the sample is out), and releases the sample only on that thread: dropped on another
// thread, it leaks the sample instead (its state is never touched there, the mapping stays).
unsafe impl Send for HeldSample {}
unsafe impl Sync for HeldSample {}

impl HeldSample {
    /// Holds `sample`, counted in `live` until dropped.
    pub fn new(sample: AirSample, live: &Arc<AtomicUsize>) -> HeldSample {
        let p = sample.payload();
        live.fetch_add(1, Ordering::AcqRel);
        HeldSample {
            bytes: p.as_ptr(),
            len: p.len(),
            sample: std::mem::ManuallyDrop::new(sample),
            thread: std::thread::current().id(),
            live: live.clone(),
        }
    }
}

impl AsBytes for HeldSample {
    fn as_bytes(&self) -> &[u8] {
        // SAFETY: the payload of the held sample, valid and unchanged while it is held.
        unsafe { std::slice::from_raw_parts(self.bytes, self.len) }
    }
}

impl Drop for HeldSample {
    fn drop(&mut self) {
        if std::thread::current().id() == self.thread {
            // SAFETY: dropped once, here, on the thread that received it.
            unsafe { std::mem::ManuallyDrop::drop(&mut self.sample) };
        }
        self.live.fetch_sub(1, Ordering::AcqRel);
    }
}

/// Robot `robot`'s inbox from the tick's air sample: its messages in (sender, seq) order,
/// decoded where they lie (zero-copy, when `zero_copy` and fewer than `held_limit` air
/// samples are held by views, `live`) or as copies; and how many were malformed. The sample
/// is released here unless views hold it.
pub fn air_inbox<M: DeserializeOwned>(
    sample: AirSample,
    robot: u32,
    zero_copy: bool,
    live: &Arc<AtomicUsize>,
    held_limit: usize,
    inbox: &mut Vec<Received<M>>,
) -> u32 {
    let h = *sample.user_header();
    if zero_copy && live.load(Ordering::Acquire) < held_limit {
        let owner: Arc<dyn AsBytes> = Arc::new(HeldSample::new(sample, live));
        decode_list(&h, robot, Some(&owner), owner.as_bytes(), inbox)
    } else {
        decode_list(&h, robot, None, sample.payload(), inbox)
    }
}

/// Decodes robot `robot`'s list of the air `bytes` (with header `h`): in place as views of
/// `owner` when given, else as copies. Returns how many were malformed.
fn decode_list<M: DeserializeOwned>(
    h: &AirHeader,
    robot: u32,
    owner: Option<&Arc<dyn AsBytes>>,
    bytes: &[u8],
    inbox: &mut Vec<Received<M>>,
) -> u32 {
    let Some(view) = AirView::new(h, bytes) else {
        return 0;
    };
    let mut malformed = 0;
    for i in view.deliveries(robot) {
        let decoded = view.message(i).and_then(|(mh, at)| {
            let m = match owner {
                Some(owner) => decode_in::<M>(&mh, owner, at),
                None => decode::<M>(&mh, &view.bytes()[at..]),
            };
            m.map(|m| Received::new(&mh, m))
        });
        match decoded {
            Some(r) => inbox.push(r),
            None => malformed += 1,
        }
    }
    malformed
}

/// The mapping of the world's data segment that a subscriber of `world/sense` or `radio/air`
/// reads its samples in, registered with the shrink guard
/// ([`crate::shrink_guard::absorb_range`]): a zero-copy view an agent keeps past its guarded
/// read (a [`crate::Blob`] into the air) reads zeros, not a SIGBUS, once a process of the user
/// truncates the segment (docs/protocol.md section 4). Found once per subscriber (the
/// publisher's static slots are one segment, mapped once), in /proc/self/maps.
#[derive(Default)]
pub(crate) struct GuardedMapping {
    /// `[start, end)` of the mapping found ((0, 0) before the first sample).
    range: (usize, usize),
}

impl GuardedMapping {
    /// Registers the mapping that holds a received sample's payload at `p`, unless it is the
    /// one registered already.
    pub(crate) fn cover(&mut self, p: *const u8) {
        let p = p as usize;
        let (start, end) = self.range;
        if start <= p && p < end {
            return;
        }
        self.range = match crate::shrink_guard::mapping_of(p) {
            Some((start, end)) => {
                if !crate::shrink_guard::absorb_range(start, end - start) {
                    static SAID: std::sync::Once = std::sync::Once::new();
                    SAID.call_once(|| {
                        eprintln!(
                            "agent: more of the world's data segments than the shrink guard \
                             keeps ({}): views into the newest are not guarded",
                            crate::shrink_guard::RANGES
                        )
                    });
                }
                (start, end)
            }
            // Not in a file's mapping (cannot happen for an iceoryx2 sample): nothing that
            // can shrink.
            None => (p, p + 1),
        };
    }
}

/// Quiets iceoryx2's own logging (it warns about the missing global config file otherwise).
pub fn quiet_logs() {
    set_log_level_from_env_or(LogLevel::Error);
}

/// How often an agent looks for the first sample of a service the world made anew.
pub(crate) const REMADE_POLL: std::time::Duration = std::time::Duration::from_micros(100);

/// Waits until `subscriber` (of `service`) has a sample to receive (true), or `keep_trying`
/// says to stop (false): an agent's wait for the world's resend into a service it made anew.
pub(crate) fn wait_for_sample<H: std::fmt::Debug + ZeroCopySend>(
    subscriber: &iceoryx2::port::subscriber::Subscriber<ipc::Service, [u8], H>,
    service: ServiceId,
    keep_trying: &dyn Fn() -> bool,
) -> TransportResult<bool> {
    let mut looks = 0u32;
    loop {
        let has = subscriber
            .has_samples()
            .map_err(|e| TransportError::Receive {
                service: service.clone(),
                source: e.into(),
            })?;
        if has {
            return Ok(true);
        }
        // keep_trying costs a syscall (the world's pid): every 100th look.
        looks += 1;
        if looks.is_multiple_of(100) && !keep_trying() {
            return Ok(false);
        }
        std::thread::sleep(REMADE_POLL);
    }
}
