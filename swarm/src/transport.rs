//! iceoryx2 plumbing of the multi-process executor: per-run configuration, service names and
//! capacities.
//!
//! Every service is created by the world, with the capacities the run needs, before any agent
//! starts; agents only open them. Each run has its own iceoryx2 prefix and root folder, so two
//! runs never see each other and a run's leftovers are easy to find and remove.

use crate::blob::AsBytes;
use crate::frames::{Action, Control, RadioHeader, Sense, WorldStatus};
use crate::scenario::Scenario;
use crate::{AgentRuntime, Behaviour};
use iceoryx2::prelude::*;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

mod error;
mod service;
pub use error::{Port, TransportError, TransportResult};
pub use service::{
    event, pub_sub, service_name, EventCapacity, EventService, PubSubCapacity, PubSubService,
    Reach, ServiceId, ShmPayload, CONTROL_NAME, STATUS_NAME,
};

/// A boxed error of any kind, and a result with it: what a process's run loop returns when
/// it mixes transport, file and scenario errors (the world process does). The functions here
/// return the typed [`TransportError`], which converts into it with `?`.
pub type Error = Box<dyn std::error::Error + Send + Sync>;
pub type Result<T> = std::result::Result<T, Error>;

pub type SenseService = PubSubService<Sense, ()>;
pub type ActService = PubSubService<Action, ()>;
pub type RadioService = PubSubService<[u8], RadioHeader>;
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

/// Subscribers one radio service must admit. Each agent holds at most radio.max_links +
/// radio.lingering_links links,
/// but the robots linked to one sender are bounded only by the swarm (links linger, and
/// "among my nearest max_links" is not symmetric). A subscription refused for capacity would
/// make delivery depend on timing, so every robot can always link to every other one. The
/// data segment is sized for it, but only the slots in use are ever touched.
pub fn radio_max_subscribers(sc: &Scenario) -> usize {
    (sc.run.robots as usize).saturating_sub(1).max(1) + RESTART_SLACK
}

/// Radio messages that can wait in one link's buffer: this tick's and the next's.
pub fn radio_buffer(sc: &Scenario) -> usize {
    2 * sc.radio.max_messages_per_tick as usize
}

/// Samples of one link that zero-copy receive may hold while Blob views refer into them
/// (`radio.zero_copy_held`). Past it (more messages a tick, a behaviour keeping views, a radio
/// delay) messages are decoded as copies, with the same content.
pub fn radio_held_per_link(sc: &Scenario) -> usize {
    sc.radio.zero_copy_held as usize
}

/// Samples a radio subscriber may borrow at once: those held, and the one being taken off.
pub fn radio_max_borrowed(sc: &Scenario) -> usize {
    radio_held_per_link(sc) + 1
}

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

/// Action frames: the agent publishes, the world subscribes; this tick's and the next's.
pub fn act_capacity() -> PubSubCapacity {
    PubSubCapacity {
        buffer: 2,
        ..sense_capacity()
    }
}

/// A robot's radio: its agent publishes, every other robot may subscribe (see
/// `radio_max_subscribers`); the world holds the service open.
pub fn radio_capacity(sc: &Scenario) -> PubSubCapacity {
    let subscribers = radio_max_subscribers(sc);
    PubSubCapacity {
        publishers: 1 + RESTART_SLACK,
        subscribers,
        nodes: subscribers + 1 + RESTART_SLACK + 1,
        buffer: radio_buffer(sc),
        borrowed: Some(radio_max_borrowed(sc)),
        history: Some(0),
        safe_overflow: None,
    }
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

/// Robot i's Sense service: the world creates it (`create`), the agent opens it.
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

/// Robot i's radio service: the world creates it (`create`), agents open it.
pub fn radio_service(
    node: &Node<ipc::Service>,
    robot: u32,
    sc: &Scenario,
    create: bool,
) -> TransportResult<RadioService> {
    pub_sub(
        node,
        ServiceId::Radio(robot),
        Reach::create_if(create, || radio_capacity(sc)),
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

/// Radio publisher of robot i (fixed-size slots: no reallocation, no lost dynamic samples).
pub fn radio_publisher(
    svc: &RadioService,
    sc: &Scenario,
) -> TransportResult<iceoryx2::port::publisher::Publisher<ipc::Service, [u8], RadioHeader>> {
    svc.publisher_builder()
        .initial_max_slice_len(sc.radio.max_message_bytes as usize)
        .allocation_strategy(AllocationStrategy::Static)
        .max_loaned_samples(1)
        .create()
        .map_err(|source| TransportError::Publisher {
            service: ServiceId::of(svc),
            source,
        })
}

/// The radio's send side in shared memory: loans exactly the message's bytes in the robot's
/// own radio service, writes the header and lets the runtime encode the message straight into
/// the slot, then sends. Used by the agent process and by the benches that time its path.
pub struct ShmTx<'a> {
    pub publisher: &'a iceoryx2::port::publisher::Publisher<ipc::Service, [u8], RadioHeader>,
    /// Loans or sends that failed (the message is lost; counted, never fatal).
    pub failures: u64,
}

impl crate::behaviour::RadioTx for ShmTx<'_> {
    fn transmit(&mut self, h: &RadioHeader, fill: &mut dyn FnMut(&mut [u8])) {
        let len = (h.len as usize).max(1);
        match self.publisher.loan_slice_uninit(len) {
            Ok(sample) => {
                // SAFETY: the slot is shared memory of the publisher's data segment, mapped
                // from tmpfs: its bytes are always initialised (zero when first mapped, then
                // whatever an earlier message left), and every u8 value is valid. `fill`
                // overwrites the first h.len bytes; a zero-length message leaves one
                // unread byte. Skipping a zeroing pass saves a write of the whole message.
                let mut sample = unsafe { sample.assume_init() };
                *sample.user_header_mut() = *h;
                fill(&mut sample.payload_mut()[..h.len as usize]);
                if sample.send().is_err() {
                    self.failures += 1;
                }
            }
            Err(_) => self.failures += 1,
        }
    }
}

/// A received radio sample kept while [`crate::Blob`] views refer into it (zero-copy
/// receive). Dropping the last view returns the sample to its publisher.
pub struct HeldSample {
    sample: std::mem::ManuallyDrop<RadioSample>,
    bytes: *const u8,
    len: usize,
    thread: std::thread::ThreadId,
    live: Arc<AtomicUsize>,
}

/// A sample taken off a radio link.
pub type RadioSample = iceoryx2::sample::Sample<ipc::Service, [u8], RadioHeader>;

// SAFETY: an iceoryx2 ipc sample is neither Send nor Sync because releasing it touches its
// subscriber's single-threaded state (an Rc). HeldSample reads only the payload bytes through
// the pointer taken on the receiving thread (shared memory that the publisher does not reuse
// while the sample is out), and releases the sample only on that thread: dropped on another
// thread, it leaks the sample instead (its state is never touched there, the mapping stays).
unsafe impl Send for HeldSample {}
unsafe impl Sync for HeldSample {}

impl HeldSample {
    /// Holds `sample`, counted in `live` until dropped.
    pub fn new(sample: RadioSample, live: &Arc<AtomicUsize>) -> HeldSample {
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

/// Hands a radio sample taken off a link to the runtime: in place (zero-copy) if the behaviour
/// asks for it (`Behaviour::zero_copy`) and the link holds fewer than `radio_held_per_link` samples (`live`), else
/// decoded at once and released.
pub fn take_radio<B: Behaviour>(
    rt: &mut AgentRuntime<B>,
    sample: RadioSample,
    live: &Arc<AtomicUsize>,
    held_limit: usize,
) {
    if rt.zero_copy() && live.load(Ordering::Acquire) < held_limit {
        let h = *sample.user_header();
        rt.ingest_held(&h, HeldSample::new(sample, live));
    } else {
        rt.ingest(sample.user_header(), sample.payload());
    }
}

/// Quiets iceoryx2's own logging (it warns about the missing global config file otherwise).
pub fn quiet_logs() {
    set_log_level_from_env_or(LogLevel::Error);
}
