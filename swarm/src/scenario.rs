//! Scenario files: types, parsing with errors that name the file and key, and validation.

use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::Path;

pub use crate::sections::agents::{AgentEntry, RobotSet};
pub use crate::sections::formation::FormationSection;
pub use crate::sections::hunt::HuntSection;
pub use crate::sections::roam::{RoamParams, ROAM_BEACON_OVERHEAD};

/// The default scenario, embedded so that `orchestrator up` needs no file.
pub const DEFAULT_SCENARIO: &str = include_str!("../../configs/default.toml");
/// The roaming scenario (an overlay of the default): what the transport benchmarks and the
/// long-running fault tests run, since a search run ends when every target is found.
pub const ROAM_SCENARIO: &str = include_str!("../../configs/roam.toml");

/// A scenario: the core's sections (typed fields) and its plug-ins' ([`Scenario::sections`]).
#[derive(Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    pub run: RunParams,
    pub arena: Arena,
    pub robot: RobotParams,
    pub radio: RadioParams,
    pub runtime: RuntimeParams,
    pub roam: RoamParams,
    pub faults: FaultParams,
    /// The plug-ins' sections (`[search]`, `[formation]`, `[hunt]`, `[cbca]`, a user's own),
    /// written after `[faults]` in the order the binary registered them (crate::plugin).
    /// Read with [`Scenario::section`].
    #[serde(skip)]
    pub sections: crate::plugin::Sections,
    /// `[[agents]]`: robots run by the user's own programs (sections/agents.rs); the robots
    /// no entry lists run `run.behaviour`. Left out when empty.
    #[serde(default)]
    pub agents: Vec<AgentEntry>,
    /// The world host's Zenoh listen endpoint in a run across hosts (`up --listen` overrides
    /// it; default `sections::hosts::DEFAULT_LISTEN`). Never resolved into the run's files.
    #[serde(default)]
    pub hosts_listen: Option<String>,
    /// `[[hosts]]`: which robots run on which remote host (`sections::hosts`). Never resolved
    /// into the run's files: where a robot runs changes no result.
    #[serde(default)]
    pub hosts: Vec<crate::sections::hosts::HostSpec>,
}

/// The core's top-level keys (every other top-level table is a plug-in's section).
pub const CORE_SECTIONS: &[&str] = &[
    "run",
    "arena",
    "robot",
    "radio",
    "runtime",
    "roam",
    "faults",
    "agents",
    "hosts_listen",
    "hosts",
];

/// Written as the resolved scenario.toml lists it: the core's sections, the plug-ins' (in
/// registration order), `[[agents]]` (if any); never `[[hosts]]` nor `hosts_listen`.
impl Serialize for Scenario {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let n = 7 + self.sections.written() + usize::from(!self.agents.is_empty());
        let mut st = s.serialize_struct("Scenario", n)?;
        st.serialize_field("run", &self.run)?;
        st.serialize_field("arena", &self.arena)?;
        st.serialize_field("robot", &self.robot)?;
        st.serialize_field("radio", &self.radio)?;
        st.serialize_field("runtime", &self.runtime)?;
        st.serialize_field("roam", &self.roam)?;
        st.serialize_field("faults", &self.faults)?;
        self.sections.serialize_into(&mut st)?;
        if !self.agents.is_empty() {
            st.serialize_field("agents", &self.agents)?;
        }
        st.end()
    }
}

#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RunParams {
    /// The agents' behaviour (the agent crate's registry lists them).
    pub behaviour: String,
    /// The world's mission (the world crate's registry lists them). Left out: the mission the
    /// behaviour implies (search -> search, otherwise roam, the empty one); a resolved scenario
    /// names it only when it was set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mission: Option<String>,
    /// Agent processes, stations included.
    pub robots: u32,
    /// The last `stations` of the `robots` agents are stations: agents with no body (no
    /// motion, no collisions, not sensed by robots' own sensors, not counted by the mission),
    /// that only talk on the radio (the hunt's auctioneer). Left out of a resolved scenario
    /// when 0.
    #[serde(default, skip_serializing_if = "is_zero_u32")]
    pub stations: u32,
    #[serde(with = "crate::toml_u64")]
    pub seed: u64,
    pub max_ticks: u64,
}

#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Arena {
    pub width: f64,
    pub height: f64,
    pub start_region: [f64; 4],
    pub boundary_spacing: f64,
    pub walls_sensed: bool,
    #[serde(default)]
    pub obstacles: Vec<Obstacle>,
    /// Disc obstacles (the formation paper's round obstacles, docs/formation.md 1.1): exact
    /// circles for the bodies' clearances, sampled into boundary points for sensing. Left out
    /// of a resolved scenario when empty, so polygon-only maps read as they always did.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub discs: Vec<DiscObstacle>,
}

/// A round obstacle: a disc of `radius` around `centre`.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DiscObstacle {
    pub name: String,
    pub centre: [f64; 2],
    pub radius: f64,
}

impl DiscObstacle {
    /// Points on the circle at most `spacing` apart (at least 8): what robots sense of it.
    pub fn boundary(&self, spacing: f64) -> Vec<[f64; 2]> {
        self.outline(self.boundary_count(spacing) as usize)
    }
    /// How many points [`DiscObstacle::boundary`] gives (saturating).
    pub fn boundary_count(&self, spacing: f64) -> u64 {
        ((std::f64::consts::TAU * self.radius / spacing).ceil() as u64).max(8)
    }
    /// Signed distance from `p` to the circle: positive outside, negative inside.
    pub fn distance(&self, p: [f64; 2]) -> f64 {
        ((p[0] - self.centre[0]).powi(2) + (p[1] - self.centre[1]).powi(2)).sqrt() - self.radius
    }
    /// `n` points on the circle, counter-clockwise from angle 0 (a polygon inscribed in it).
    pub fn outline(&self, n: usize) -> Vec<[f64; 2]> {
        (0..n.max(3))
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n.max(3) as f64;
                [
                    self.centre[0] + self.radius * a.cos(),
                    self.centre[1] + self.radius * a.sin(),
                ]
            })
            .collect()
    }
}

#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Obstacle {
    pub name: String,
    pub points: Vec<[f64; 2]>,
}

#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RobotParams {
    pub v_max: f64,
    pub sensing_radius: f64,
    /// Radius of the robot's disc body (0: point robots). With a body the world keeps discs
    /// out of obstacles and walls, places robots apart, and measures every tick the clearances
    /// and the overlapping pairs (summary `mission.body`, recording version 2). Left out of a
    /// resolved scenario when 0, so point-robot scenarios read as they always did.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub radius: f64,
    /// Other robots a robot senses itself (Sense `nearby`: positions and velocities) within
    /// this distance; 0: none (robots learn of each other only over the radio). Left out of a
    /// resolved scenario when 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub neighbour_sensing_radius: f64,
    /// How a command moves the robot. Left out of a resolved scenario when holonomic.
    #[serde(default, skip_serializing_if = "Kinematics::is_holonomic")]
    pub kinematics: Kinematics,
}

/// How the world integrates a robot's command (one tick is the control step: speeds are per
/// tick, turn rates in radians per tick).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Default)]
#[serde(tag = "model", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Kinematics {
    /// The command is a velocity (vx, vy), |v| <= v_max; the heading follows the motion.
    #[default]
    Holonomic,
    /// The command is (v, w): speed |v| <= v_max along the heading and turn rate |w| <= w_max
    /// (docs/hunting.md eqs. 2.8-2.10: x += v cos(phi), y += v sin(phi), then phi += w).
    Unicycle { w_max: f64 },
}

impl Kinematics {
    pub fn is_holonomic(&self) -> bool {
        *self == Kinematics::Holonomic
    }
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

fn is_zero_u32(x: &u32) -> bool {
    *x == 0
}

#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum LossModel {
    Bernoulli,
    Distance,
}

#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RadioParams {
    pub comm_radius: f64,
    pub loss_model: LossModel,
    pub loss: f64,
    pub loss_at_range: f64,
    pub loss_exponent: f64,
    pub delay_ticks: u32,
    pub max_message_bytes: u32,
    pub max_messages_per_tick: u32,
    /// Air samples an agent may hold while zero-copy views refer into them
    /// (`Behaviour::zero_copy`).
    #[serde(default = "default_zero_copy_held")]
    pub zero_copy_held: u32,
    /// Bytes (headers included) a robot may put on the air per tick; the excess of a tick is
    /// dropped and counted (`dropped_bandwidth`). 0: no cap.
    #[serde(default)]
    pub bandwidth_bytes_per_tick: u32,
    /// Bursty loss: a Gilbert-Elliott chain per directed link instead of `loss_model`.
    #[serde(default)]
    pub burst: Option<crate::radio::BurstParams>,
    /// Obstacles block the line of sight between sender and receiver.
    #[serde(default)]
    pub occlusion: bool,
    /// Agents whose transmissions have a range of their own instead of `comm_radius` (a
    /// station's stronger transmitter, a robot's weaker one): the medium judges a message by
    /// its sender's range (`world::medium`). Empty: every agent has `comm_radius`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sender_ranges: Vec<SenderRange>,
    /// How the medium finds the receivers within a sender's range: a grid of the live robots
    /// (default), or every robot (the scan before the grid, for benchmarks). Both give the
    /// same deliveries.
    #[serde(default, skip_serializing_if = "RangeScan::is_grid")]
    pub range_scan: RangeScan,
}

/// `[[radio.sender_ranges]]`: one agent's own radio range.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SenderRange {
    /// The agent (robot or station id, 0..run.robots).
    pub agent: u32,
    /// Its messages reach receivers within this distance (replaces `radio.comm_radius` for
    /// them; the distance loss model scales with it).
    pub comm_radius: f64,
}

/// `radio.range_scan`: how the medium finds the receivers a broadcast may reach.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum RangeScan {
    /// The cells of a grid of the live robots within the sender's range.
    #[default]
    Grid,
    /// Every live robot (O(N^2) a tick; kept for the benchmark and the grid's tests).
    All,
}

impl RangeScan {
    fn is_grid(&self) -> bool {
        *self == RangeScan::Grid
    }
}

impl RadioParams {
    /// Each agent's radio range, by id (`sender_ranges`, else `comm_radius`), for `n` agents.
    pub fn ranges(&self, n: usize) -> Vec<f64> {
        let mut r = vec![self.comm_radius; n];
        for s in &self.sender_ranges {
            if let Some(x) = r.get_mut(s.agent as usize) {
                *x = s.comm_radius;
            }
        }
        r
    }
}

fn default_zero_copy_held() -> u32 {
    0
}

#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum BarrierKind {
    /// One futex word in shared memory wakes every agent; agents count themselves back.
    Futex,
    /// The same barrier, woken through iceoryx2 events (one notify to N listeners, N
    /// notifiers back): slower, kept for comparison.
    Iox2Event,
}

/// How the actions travel from each agent to the world (`runtime.acts`, docs/protocol.md
/// section 5): both are iceoryx2, world-created, one service per robot.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum ActsKind {
    /// Publish-subscribe `robot/<i>/act` (the default): a loaned sample a tick, the Action as
    /// its user header, the messages as its payload.
    #[default]
    PubSub,
    /// Blackboard `robot/<i>/board`: the agent's writer updates the act value (two tick
    /// slots, an attach key), the world's reader copies it: no loan, no queue (BENCHMARKS
    /// 22b: a quarter of pub-sub's instructions; 25: 1.13-1.29x pub-sub's ticks/s on roam).
    /// One host only for now: a remote robot's restart over boards is racy (DESIGN-NOTES).
    Blackboard,
}

impl ActsKind {
    fn is_default(&self) -> bool {
        *self == ActsKind::default()
    }
}

#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RuntimeParams {
    pub barrier: BarrierKind,
    /// The act transport (`ActsKind`); left out of a resolved scenario when it is the
    /// default, so recordings of runs that do not set it are unchanged.
    #[serde(default, skip_serializing_if = "ActsKind::is_default")]
    pub acts: ActsKind,
    pub ack_deadline_ms: u64,
    pub poll_ms: u64,
    pub startup_timeout_s: u64,
    /// Pacing: at most this many ticks per second (0 = as fast as the agents allow). Still
    /// lock-step (every live agent is waited for), so results do not depend on it.
    #[serde(default)]
    pub tick_hz: f64,
    /// Real-time mode (`--realtime HZ`, DESIGN section 3): the world ticks on a clock at this
    /// rate, tick k's deadline being t0 + (k + 1) / realtime_hz; an action that misses it is
    /// not waited for (the robot keeps its last command) and counts as a deadline miss.
    /// 0 = lock-step (the default, deterministic). Left out of a resolved scenario when 0, so
    /// lock-step files and recordings are unchanged; a real-time run's resolved scenario (and
    /// so its recording's header) names its rate.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub realtime_hz: f64,
    /// Record the messages each robot was handed every tick (recording version 7: sender,
    /// seq and size of each), for the viewer's "heard this tick". Off by default: a run that
    /// leaves it off records what it did before (and its resolved scenario does not list it).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub record_deliveries: bool,
}

impl RuntimeParams {
    /// Whether the world ticks on a clock (`realtime_hz` > 0) rather than in lock-step.
    pub fn is_realtime(&self) -> bool {
        self.realtime_hz > 0.0
    }

    /// Real-time mode: when tick `k` starts (k / realtime_hz) and its deadline
    /// ((k + 1) / realtime_hz), counted from the start of the loop. None in lock-step.
    pub fn realtime_window(&self, k: u64) -> Option<(std::time::Duration, std::time::Duration)> {
        let at = |t: u64| {
            std::time::Duration::try_from_secs_f64(t as f64 / self.realtime_hz)
                .unwrap_or(std::time::Duration::MAX)
        };
        self.is_realtime().then(|| (at(k), at(k + 1)))
    }

    /// When tick `k` may start, counted from the start of the loop (None: unpaced).
    pub fn tick_start(&self, k: u64) -> Option<std::time::Duration> {
        // Saturating: a pace so slow that tick k lies beyond Duration's range (`--tick-hz
        // 1e-300`) never starts it, instead of panicking.
        (self.tick_hz > 0.0).then(|| {
            std::time::Duration::try_from_secs_f64(k as f64 / self.tick_hz)
                .unwrap_or(std::time::Duration::MAX)
        })
    }

    /// Sleeps until tick `k` may start (a no-op when unpaced or already late).
    pub fn pace(&self, loop_start: std::time::Instant, k: u64) {
        if let Some(at) = self.tick_start(k) {
            let now = loop_start.elapsed();
            if at > now {
                std::thread::sleep(at - now);
            }
        }
    }
}

/// What happens to a robot whose agent process dies.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum FaultPolicy {
    /// The robot stands still as an obstacle; the swarm carries on.
    Drop,
    /// The orchestrator starts a new agent for the robot, which starts fresh from its Sense.
    Restart,
}

#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FaultParams {
    pub on_fault: FaultPolicy,
    pub max_restarts: u32,
    pub chaos_rate: f64,
    /// Scheduled SIGKILLs as [tick, robot]; the resolved scenario lists the random ones too.
    pub kill_at: Vec<[u64; 2]>,
    /// This fraction of the robots (rounded) is killed once each, at seeded random ticks
    /// within `kill_window` (`--kill-fraction`).
    pub kill_fraction: f64,
    /// [first, last] tick of the `kill_fraction` kills.
    pub kill_window: [u64; 2],
}

/// Hard limits that come from the fixed-size frames.
pub const MAX_ROBOTS: u32 = 4096;

/// Longest run (`run.max_ticks`), and the last tick a kill may be scheduled at: 10^8 ticks is
/// over a day at 1,000 ticks/s.
pub const MAX_TICKS: u64 = 100_000_000;

/// Most polygon obstacles (`[[arena.obstacles]]`): every robot's sensing and every occlusion
/// test walks them (the maps of the papers have 5 to 9).
pub const MAX_OBSTACLES: usize = 1024;

/// Most corners of one polygon obstacle.
pub const MAX_OBSTACLE_CORNERS: usize = 4096;

/// Most disc obstacles (`[[arena.discs]]`): each is a constraint of every robot at every node
/// of the formation's pattern optimiser and of every ORCA step (the paper has 2). 10,000
/// discs kept the optimiser 12 minutes in one tick (issue 37).
pub const MAX_DISCS: usize = 64;

/// Slowest pacing, in ticks per second (one tick per 1,000 s): below it a tick's start time
/// k / tick_hz no longer fits a `Duration` for long runs, and nobody watches a run that slow.
pub const MIN_TICK_HZ: f64 = 1e-3;
/// Slowest real-time rate (`runtime.realtime_hz`, ticks per second): one tick per 100 s; a
/// slower clock is pacing, for which `runtime.tick_hz` is the key.
pub const MIN_REALTIME_HZ: f64 = 0.01;
/// Fastest real-time rate: a 100 us tick, already below one wake-up round of 50 agents on
/// this kind of VM (BENCHMARKS.md); faster only measures the clock.
pub const MAX_REALTIME_HZ: f64 = 10_000.0;
/// Most restarts a robot may have (`faults.max_restarts`): more than any run needs.
pub const MAX_RESTARTS: u32 = 1_000_000;
/// Fastest pacing (ticks per second); faster than any run goes unpaced.
pub const MAX_TICK_HZ: f64 = 1e6;

/// A bad scenario: which file (or flag), which key, what is allowed.
#[derive(Debug, Clone, PartialEq)]
pub struct ConfigError {
    pub source: String,
    pub key: String,
    pub message: String,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.key.is_empty() {
            write!(f, "{}: {}", self.source, self.message)
        } else {
            write!(f, "{}: `{}` {}", self.source, self.key, self.message)
        }
    }
}

impl std::error::Error for ConfigError {}

/// Range checks that name the key, where its value came from and the allowed range: the
/// scenario's own validation and every behaviour's and mission's use it.
pub struct Check<'a> {
    /// Where a key's value came from (a flag, or the file).
    pub key_source: &'a dyn Fn(&str) -> String,
}

impl Check<'_> {
    /// An error for `key`; its source names where the key is written (`file:LINE`, or the
    /// default's line when the file does not hold it; a flag as it is).
    pub fn err(&self, key: &str, message: String) -> ConfigError {
        ConfigError {
            source: crate::key_lines::locate(&(self.key_source)(key), key),
            key: key.to_string(),
            message,
        }
    }
    /// `v` in lo..=hi.
    pub fn range_u(&self, key: &str, v: u64, lo: u64, hi: u64) -> Result<(), ConfigError> {
        if v < lo || v > hi {
            Err(self.err(key, format!("= {v} is out of range: allowed {lo}..={hi}")))
        } else {
            Ok(())
        }
    }
    /// `v` finite and in [lo, hi] (or (lo, hi] with `lo_open`).
    pub fn range_f(
        &self,
        key: &str,
        v: f64,
        lo: f64,
        hi: f64,
        lo_open: bool,
    ) -> Result<(), ConfigError> {
        let below = if lo_open { v <= lo } else { v < lo };
        if !v.is_finite() || below || v > hi {
            let l = if lo_open { "(" } else { "[" };
            Err(self.err(
                key,
                format!("= {} is out of range: allowed {l}{lo}, {hi}]", number(v)),
            ))
        } else {
            Ok(())
        }
    }
}

/// A number as an error shows it: plain, or in exponent form when tiny or huge (1e-300, a
/// subnormal 5e-324 rather than its 324 digits).
pub fn number(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e15).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Numbers as an error shows them: `[1, 5e-324]`.
pub fn numbers(v: &[f64]) -> String {
    let parts: Vec<String> = v.iter().map(|x| number(*x)).collect();
    format!("[{}]", parts.join(", "))
}

/// Serde's "invalid value: integer `-1`, expected u32" with the allowed range appended, so
/// that an overflow names its range as every other refusal does.
fn with_integer_range(message: &str) -> String {
    let ranges = [
        ("u8", u8::MAX as u64),
        ("u16", u16::MAX as u64),
        ("u32", u32::MAX as u64),
        ("u64", u64::MAX),
        ("usize", usize::MAX as u64),
    ];
    for (ty, max) in ranges {
        if message.trim_end().ends_with(&format!("expected {ty}")) {
            return format!("{message}: allowed 0..={max}");
        }
    }
    message.to_string()
}

impl Default for Scenario {
    fn default() -> Self {
        Scenario::parse(DEFAULT_SCENARIO, crate::key_lines::DEFAULT_SOURCE)
            .expect("the embedded default scenario parses")
    }
}

impl Scenario {
    /// The embedded roaming scenario (configs/roam.toml over the default).
    pub fn roam() -> Scenario {
        Scenario::parse(ROAM_SCENARIO, "embedded roam scenario")
            .expect("the embedded roam scenario parses")
    }

    /// Parses a scenario. Keys missing from `text` take the embedded default's values, so a
    /// file needs to hold only what it changes; unknown keys are errors.
    ///
    /// Errors name the file and line (`file.toml:12`) and the key path
    /// (`arena.obstacles[3].points`); a key the file does not hold names the default's line.
    pub fn parse(text: &str, source: &str) -> Result<Scenario, ConfigError> {
        let mut base: toml::Table = DEFAULT_SCENARIO.parse().map_err(|e| ConfigError {
            source: crate::key_lines::DEFAULT_SOURCE.into(),
            key: String::new(),
            message: format!("{e}"),
        })?;
        let user: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            // A syntax error: the parser knows the line; the key written there, if any.
            let at = e.span().map(|s| s.start).unwrap_or(0);
            let line = crate::key_lines::line_of_offset(text, at);
            let mut message = format!("not valid TOML: {}", e.message().trim());
            if message.contains("number too large") {
                message += &format!(" (TOML integers are {}..={})", i64::MIN, i64::MAX);
            }
            ConfigError {
                source: format!("{source}:{line}"),
                key: crate::key_lines::key_at_line(text, line).unwrap_or_default(),
                message,
            }
        })?;
        crate::scenario_shape::check(&user, text, source)?;
        merge(&mut base, user);
        let plugins: toml::Table = base
            .keys()
            .filter(|k| !CORE_SECTIONS.contains(&k.as_str()))
            .cloned()
            .collect::<Vec<_>>()
            .into_iter()
            .filter_map(|k| base.remove(&k).map(|v| (k, v)))
            .collect();
        let mut sc: Scenario = serde_path_to_error::deserialize(toml::Value::Table(base)).map_err(
            |e: serde_path_to_error::Error<toml::de::Error>| {
                let path = e.path().to_string();
                let key = if path == "." { String::new() } else { path };
                ConfigError {
                    source: crate::key_lines::locate_in(source, text, &key),
                    message: with_integer_range(e.inner().message()),
                    key,
                }
            },
        )?;
        sc.sections = crate::plugin::Sections::read(plugins).map_err(|(name, message, path)| {
            let path = path.to_string();
            let key = if path == "." {
                name
            } else {
                format!("{name}.{path}")
            };
            ConfigError {
                source: crate::key_lines::locate_in(source, text, &key),
                message: with_integer_range(&message),
                key,
            }
        })?;
        Ok(sc)
    }

    /// The formation paper's section (only formation scenarios have one).
    pub fn formation(&self) -> Option<&FormationSection> {
        self.section::<FormationSection>()
    }
    pub fn formation_mut(&mut self) -> Option<&mut FormationSection> {
        self.sections.get_mut::<FormationSection>()
    }
    pub fn set_formation(&mut self, f: Option<FormationSection>) {
        match f {
            Some(f) => self.sections.set(f),
            None => self.sections.remove::<FormationSection>(),
        }
    }
    /// The hunting thesis's section (empty: no hunt).
    pub fn hunt(&self) -> &HuntSection {
        self.section::<HuntSection>().expect("[hunt] has a default")
    }
    pub fn hunt_mut(&mut self) -> &mut HuntSection {
        self.sections
            .get_mut::<HuntSection>()
            .expect("[hunt] has a default")
    }
    /// The `[cbca]` section (thesis 003 chapter 4), read by the agent crate's cbca behaviour.
    pub fn cbca(&self) -> &toml::Table {
        &self
            .section::<crate::sections::cbca::CbcaSection>()
            .expect("[cbca] has a default")
            .0
    }
    pub fn cbca_mut(&mut self) -> &mut toml::Table {
        &mut self
            .sections
            .get_mut::<crate::sections::cbca::CbcaSection>()
            .expect("[cbca] has a default")
            .0
    }

    /// Plug-in section `S` (None: the scenario has none and `S` has no default).
    pub fn section<S: crate::plugin::Section>(&self) -> Option<&S> {
        self.sections.get::<S>()
    }

    pub fn load(path: &Path) -> Result<Scenario, ConfigError> {
        let source = path.display().to_string();
        let text = crate::scenario_shape::read_bounded(path).map_err(|message| ConfigError {
            source: source.clone(),
            key: String::new(),
            message,
        })?;
        let mut sc = Scenario::parse(&text, &source)?;
        // `[[agents]]` paths are relative to the file's folder, wherever the program runs.
        if !sc.agents.is_empty() {
            let dir = path
                .parent()
                .filter(|d| !d.as_os_str().is_empty())
                .unwrap_or(Path::new("."));
            let dir = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
            let file = dir.join(path.file_name().unwrap_or_default());
            crate::sections::agents::resolve_paths(
                &mut sc.agents,
                &dir,
                &file.display().to_string(),
            );
        }
        Ok(sc)
    }

    /// Robots with a body: agents 0..bodies() (the stations come after them).
    pub fn bodies(&self) -> u32 {
        self.run.robots.saturating_sub(self.run.stations)
    }

    /// Whether agent `id` is a station (no body; see `run.stations`).
    pub fn is_station(&self, id: u32) -> bool {
        id >= self.bodies() && id < self.run.robots
    }

    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).expect("scenario serialises")
    }

    /// Checks every value of the sections every run has against its allowed range (the
    /// behaviour's and the mission's own sections are checked by their owners, with the same
    /// [`Check`]). `key_source` maps a key to where its value came from (a flag such as
    /// `--robots`, or the file name).
    pub fn validate(&self, key_source: &dyn Fn(&str) -> String) -> Result<(), ConfigError> {
        let c = Check { key_source };
        c.range_u("run.robots", self.run.robots as u64, 1, MAX_ROBOTS as u64)?;
        c.range_u(
            "run.stations",
            self.run.stations as u64,
            0,
            self.run.robots as u64 - 1,
        )
        .map_err(|mut e| {
            e.message += " (stations are among run.robots, and one robot at least has a body)";
            e
        })?;
        c.range_u("run.max_ticks", self.run.max_ticks, 1, MAX_TICKS)?;
        c.range_f("arena.width", self.arena.width, 0.0, 1e7, true)?;
        c.range_f("arena.height", self.arena.height, 0.0, 1e7, true)?;
        let [x0, y0, x1, y1] = self.arena.start_region;
        if !(0.0 <= x0 && x0 < x1 && x1 <= self.arena.width && 0.0 <= y0 && y0 < y1)
            || y1 > self.arena.height
        {
            return Err(c.err(
                "arena.start_region",
                format!(
                    "= {} must be [x0, y0, x1, y1] with 0 <= x0 < x1 <= width and 0 <= y0 < y1 <= height",
                    numbers(&self.arena.start_region)
                ),
            ));
        }
        c.range_u(
            "arena.obstacles",
            self.arena.obstacles.len() as u64,
            0,
            MAX_OBSTACLES as u64,
        )
        .map_err(|mut e| {
            e.message = format!(
                "has {} entries: at most {MAX_OBSTACLES} polygons (MAX_OBSTACLES)",
                self.arena.obstacles.len()
            );
            e
        })?;
        c.range_u(
            "arena.discs",
            self.arena.discs.len() as u64,
            0,
            MAX_DISCS as u64,
        )
        .map_err(|mut e| {
            e.message = format!(
                "has {} entries: at most {MAX_DISCS} discs (MAX_DISCS: each is a constraint \
                     of every robot in the pattern optimiser and in ORCA)",
                self.arena.discs.len()
            );
            e
        })?;
        c.range_f(
            "arena.boundary_spacing",
            self.arena.boundary_spacing,
            0.0,
            100.0,
            true,
        )?;
        for (i, o) in self.arena.obstacles.iter().enumerate() {
            if o.points.len() > MAX_OBSTACLE_CORNERS {
                return Err(c.err(
                    &format!("arena.obstacles[{i}].points"),
                    format!(
                        "(obstacle {}) has {} corners: at most {MAX_OBSTACLE_CORNERS} \
                         (MAX_OBSTACLE_CORNERS)",
                        crate::scenario_shape::shown(&o.name),
                        o.points.len()
                    ),
                ));
            }
            if o.points.len() < 3
                || o.points
                    .iter()
                    .any(|p| !p[0].is_finite() || !p[1].is_finite())
            {
                return Err(c.err(
                    &format!("arena.obstacles[{i}].points"),
                    format!(
                        "(obstacle {}) must hold at least 3 finite [x, y] points",
                        crate::scenario_shape::shown(&o.name)
                    ),
                ));
            }
            let (w, h) = (self.arena.width, self.arena.height);
            if let Some((j, p)) = o
                .points
                .iter()
                .enumerate()
                .find(|(_, p)| !(0.0..=w).contains(&p[0]) || !(0.0..=h).contains(&p[1]))
            {
                return Err(c.err(
                    &format!("arena.obstacles[{i}].points[{j}]"),
                    format!(
                        "= {} (obstacle {}) lies outside the arena [0, {}] x [0, {}]",
                        numbers(p),
                        crate::scenario_shape::shown(&o.name),
                        number(w),
                        number(h)
                    ),
                ));
            }
        }
        for (i, d) in self.arena.discs.iter().enumerate() {
            let (w, h) = (self.arena.width, self.arena.height);
            let [x, y] = d.centre;
            if !(x.is_finite() && y.is_finite() && (0.0..=w).contains(&x) && (0.0..=h).contains(&y))
            {
                return Err(c.err(
                    &format!("arena.discs[{i}].centre"),
                    format!(
                        "= {} (disc {}) must be finite and inside the arena [0, {}] x [0, {}]",
                        numbers(&d.centre),
                        crate::scenario_shape::shown(&d.name),
                        number(w),
                        number(h)
                    ),
                ));
            }
            c.range_f(
                &format!("arena.discs[{i}].radius"),
                d.radius,
                0.0,
                1e6,
                true,
            )?;
        }
        c.range_f("robot.v_max", self.robot.v_max, 0.0, 1e6, true)?;
        c.range_f(
            "robot.sensing_radius",
            self.robot.sensing_radius,
            0.0,
            1e7,
            false,
        )?;
        c.range_f("robot.radius", self.robot.radius, 0.0, 1e6, false)?;
        c.range_f(
            "robot.neighbour_sensing_radius",
            self.robot.neighbour_sensing_radius,
            0.0,
            1e7,
            false,
        )?;
        if let Kinematics::Unicycle { w_max } = self.robot.kinematics {
            c.range_f(
                "robot.kinematics.w_max",
                w_max,
                0.0,
                std::f64::consts::PI,
                true,
            )?;
        }
        c.range_f("radio.comm_radius", self.radio.comm_radius, 0.0, 1e7, false)?;
        c.range_f("radio.loss", self.radio.loss, 0.0, 1.0, false)?;
        c.range_f(
            "radio.loss_at_range",
            self.radio.loss_at_range,
            0.0,
            1.0,
            false,
        )?;
        c.range_f(
            "radio.loss_exponent",
            self.radio.loss_exponent,
            0.0,
            100.0,
            true,
        )?;
        c.range_u("radio.delay_ticks", self.radio.delay_ticks as u64, 0, 1000)?;
        let mut ranged = std::collections::BTreeSet::new();
        for (k, r) in self.radio.sender_ranges.iter().enumerate() {
            let key = format!("radio.sender_ranges[{k}]");
            c.range_u(
                &format!("{key}.agent"),
                r.agent as u64,
                0,
                self.run.robots as u64 - 1,
            )?;
            c.range_f(
                &format!("{key}.comm_radius"),
                r.comm_radius,
                0.0,
                1e7,
                false,
            )?;
            // (With the range check above this also bounds the list by run.robots.)
            if !ranged.insert(r.agent) {
                return Err(c.err(
                    &format!("{key}.agent"),
                    format!("= {}: this agent already has a range", r.agent),
                ));
            }
        }
        if let Some(b) = &self.radio.burst {
            for (key, v) in [
                ("radio.burst.p_good_bad", b.p_good_bad),
                ("radio.burst.p_bad_good", b.p_bad_good),
                ("radio.burst.loss_good", b.loss_good),
                ("radio.burst.loss_bad", b.loss_bad),
            ] {
                c.range_f(key, v, 0.0, 1.0, false)?;
            }
        }
        c.range_u(
            "radio.bandwidth_bytes_per_tick",
            self.radio.bandwidth_bytes_per_tick as u64,
            0,
            u32::MAX as u64,
        )?;
        c.range_u(
            "radio.zero_copy_held",
            self.radio.zero_copy_held as u64,
            0,
            64,
        )?;
        c.range_u(
            "radio.max_message_bytes",
            self.radio.max_message_bytes as u64,
            8,
            65_536,
        )?;
        c.range_u(
            "radio.max_messages_per_tick",
            self.radio.max_messages_per_tick as u64,
            1,
            crate::frames::MAX_SENT as u64,
        )?;
        c.range_u(
            "runtime.ack_deadline_ms",
            self.runtime.ack_deadline_ms,
            10,
            600_000,
        )?;
        c.range_u("runtime.poll_ms", self.runtime.poll_ms, 1, 10_000)?;
        // 0 is unpaced; otherwise the period 1 / tick_hz (and k / tick_hz for every tick k)
        // must fit a Duration: below MIN_TICK_HZ a tick would last over a quarter of an hour.
        if self.runtime.tick_hz != 0.0 {
            c.range_f(
                "runtime.tick_hz",
                self.runtime.tick_hz,
                MIN_TICK_HZ,
                MAX_TICK_HZ,
                false,
            )
            .map_err(|mut e| {
                e.message += " (or 0: unpaced)";
                e
            })?;
        }
        // 0 is lock-step; a real-time clock has its own pace, so tick_hz must be 0 with it.
        if self.runtime.realtime_hz != 0.0 {
            c.range_f(
                "runtime.realtime_hz",
                self.runtime.realtime_hz,
                MIN_REALTIME_HZ,
                MAX_REALTIME_HZ,
                false,
            )
            .map_err(|mut e| {
                e.message += " ticks per second (or 0: lock-step)";
                e
            })?;
            if self.runtime.tick_hz != 0.0 {
                return Err(c.err(
                    "runtime.realtime_hz",
                    format!(
                        "= {} cannot be combined with runtime.tick_hz = {}: real-time mode \
                         ticks on its own clock; set runtime.tick_hz = 0 (pacing is for \
                         lock-step runs)",
                        number(self.runtime.realtime_hz),
                        number(self.runtime.tick_hz)
                    ),
                ));
            }
        }
        c.range_u(
            "runtime.startup_timeout_s",
            self.runtime.startup_timeout_s,
            1,
            3600,
        )?;
        c.range_u(
            "faults.max_restarts",
            self.faults.max_restarts as u64,
            0,
            MAX_RESTARTS as u64,
        )?;
        self.validate_faults(&|key, message| c.err(key, message))?;
        crate::sections::agents::validate(&self.agents, self.run.robots, &c)?;
        crate::sections::hosts::validate(self, &c)
    }

    /// The sections of one behaviour or mission (`[roam]`, `[search]`, `[formation]`,
    /// `[hunt]`, `[cbca]`) that this scenario sets: those that differ from the embedded
    /// default's (so a resolved scenario.toml, which lists every section, reads back as its
    /// run wrote it).
    pub fn sections_set(&self) -> Vec<String> {
        let d = Scenario::default();
        let mut out = Vec::new();
        if self.roam != d.roam {
            out.push("roam".to_string());
        }
        out.extend(self.sections.set_apart_from(&d.sections));
        out
    }

    /// Refuses a section the run does not use (issue 37: a roam run took `[formation]
    /// epsilon = -1` without a word): `used` are the sections of the run's behaviour and
    /// mission, named in the error with them.
    pub fn check_sections_used(
        &self,
        used: &[&str],
        mission: &str,
        c: &Check,
    ) -> Result<(), ConfigError> {
        if let Some(u) = self.sections.unknown().first() {
            let mut allowed: Vec<&str> = CORE_SECTIONS.to_vec();
            allowed.retain(|k| *k != "hosts_listen");
            let registered = crate::plugin::registered();
            allowed.extend(registered.iter().map(|e| e.name));
            return Err(c.err(
                u,
                format!(
                    "is not a section of a scenario: allowed {}",
                    allowed
                        .iter()
                        .map(|a| format!("[{a}]"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
        match self
            .sections_set()
            .into_iter()
            .find(|s| !used.contains(&s.as_str()))
        {
            None => Ok(()),
            Some(s) => Err(c.err(
                &s,
                format!(
                    "is a section this run does not use: its behaviour is {} and its mission \
                     {mission:?}, which read {}; remove the section, or set run.behaviour to \
                     the behaviour it is for",
                    crate::scenario_shape::shown(&self.run.behaviour),
                    if used.is_empty() {
                        "no section of their own".to_string()
                    } else {
                        used.iter()
                            .map(|u| format!("[{u}]"))
                            .collect::<Vec<_>>()
                            .join(" and ")
                    }
                ),
            )),
        }
    }

    fn validate_faults(&self, e: &dyn Fn(&str, String) -> ConfigError) -> Result<(), ConfigError> {
        let f = &self.faults;
        if !(f.chaos_rate.is_finite() && (0.0..=100.0).contains(&f.chaos_rate)) {
            return Err(e(
                "faults.chaos_rate",
                format!(
                    "= {} is out of range: allowed [0, 100] kills per 100 ticks",
                    number(f.chaos_rate)
                ),
            ));
        }
        // A kill past MAX_TICKS can never happen (and a tick above i64::MAX has no TOML
        // integer for the resolved scenario: `--chaos-at 9223372036854775808:0` panicked).
        if let Some((k, [t, _])) = f
            .kill_at
            .iter()
            .enumerate()
            .find(|(_, [t, _])| *t > MAX_TICKS)
        {
            return Err(e(
                &format!("faults.kill_at[{k}]"),
                format!("names tick {t}: allowed ticks 0..={MAX_TICKS} (MAX_TICKS)"),
            ));
        }
        for (i, t) in f.kill_window.iter().enumerate() {
            if *t > MAX_TICKS {
                return Err(e(
                    &format!("faults.kill_window[{i}]"),
                    format!("= {t} is out of range: allowed 0..={MAX_TICKS} (MAX_TICKS)"),
                ));
            }
        }
        if let Some((k, [t, r])) = f
            .kill_at
            .iter()
            .enumerate()
            .find(|(_, k)| k[1] >= self.run.robots as u64)
        {
            return Err(e(
                &format!("faults.kill_at[{k}]"),
                format!(
                    "names robot {r} (at tick {t}), but the run has robots 0..={}",
                    self.run.robots - 1
                ),
            ));
        }
        if !(f.kill_fraction.is_finite() && (0.0..=1.0).contains(&f.kill_fraction)) {
            return Err(e(
                "faults.kill_fraction",
                format!(
                    "= {} is out of range: allowed [0, 1]",
                    number(f.kill_fraction)
                ),
            ));
        }
        let [t0, t1] = f.kill_window;
        if t0 > t1 {
            return Err(e(
                "faults.kill_window",
                format!("= [{t0}, {t1}]: the first tick must not be after the last"),
            ));
        }
        Ok(())
    }
}

/// Recursively overlays `over` onto `base` (tables merge, everything else replaces).
pub(crate) fn merge(base: &mut toml::Table, over: toml::Table) {
    for (k, v) in over {
        match (base.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge(b, o),
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(_: &str) -> String {
        "test.toml".into()
    }

    #[test]
    fn embedded_default_is_valid() {
        let sc = Scenario::default();
        sc.validate(&file).unwrap();
        assert_eq!(sc.run.robots, 50);
        assert_eq!(sc.run.behaviour, "search");
        assert!(sc.sections.names().any(|n| n == "search"));
        assert_eq!(sc.arena.obstacles.len(), 9);
        let roam = Scenario::roam();
        roam.validate(&file).unwrap();
        assert_eq!(roam.run.behaviour, "roam");
        assert_eq!(roam.arena.obstacles.len(), 5);
    }

    #[test]
    fn partial_file_overrides_only_its_keys() {
        let sc = Scenario::parse("[run]\nrobots = 7\n", "t.toml").unwrap();
        assert_eq!(sc.run.robots, 7);
        assert_eq!(sc.radio.comm_radius, 300.0);
    }

    #[test]
    fn unknown_key_is_named() {
        let err = Scenario::parse("[radio]\ncomm_radiuss = 3\n", "t.toml").unwrap_err();
        assert!(err.to_string().contains("comm_radiuss"), "{err}");
        assert!(err.to_string().contains("t.toml"), "{err}");
    }

    #[test]
    fn out_of_range_values_name_key_and_range() {
        let mut sc = Scenario::default();
        sc.radio.loss = 1.5;
        let err = sc.validate(&file).unwrap_err();
        assert_eq!(err.key, "radio.loss");
        assert!(err.to_string().contains("[0, 1]"), "{err}");
        let mut sc = Scenario::default();
        sc.run.robots = 0;
        assert_eq!(sc.validate(&file).unwrap_err().key, "run.robots");
        let mut sc = Scenario::default();
        sc.radio.burst = Some(crate::radio::BurstParams {
            p_good_bad: 0.1,
            p_bad_good: 1.5,
            loss_good: 0.0,
            loss_bad: 1.0,
        });
        let err = sc.validate(&file).unwrap_err();
        assert_eq!(err.key, "radio.burst.p_bad_good");
        assert!(err.to_string().contains("[0, 1]"), "{err}");
    }

    #[test]
    fn the_medium_keys_parse() {
        let sc = Scenario::parse(
            "[radio]\nbandwidth_bytes_per_tick = 300\nocclusion = true\n\
             [radio.burst]\np_good_bad = 0.05\np_bad_good = 0.25\nloss_good = 0.0\nloss_bad = 0.8\n",
            "t.toml",
        )
        .unwrap();
        assert_eq!(sc.radio.bandwidth_bytes_per_tick, 300);
        assert!(sc.radio.occlusion);
        assert_eq!(sc.radio.burst.unwrap().p_bad_good, 0.25);
        let e = Scenario::parse("[radio.burst]\np_good_bad = 0.1\n", "t.toml").unwrap_err();
        assert!(e.to_string().contains("p_bad_good"), "{e}");
        let e = Scenario::parse("[radio]\nmax_links = 3\n", "t.toml").unwrap_err();
        assert!(e.to_string().contains("max_links"), "{e}");
    }

    #[test]
    fn sender_ranges_parse_and_are_validated() {
        let text = "[run]\nrobots = 4\n[radio]\ncomm_radius = 50.0\nrange_scan = \"all\"\n\
                    [[radio.sender_ranges]]\nagent = 3\ncomm_radius = 900.0\n";
        let sc = Scenario::parse(text, "t.toml").unwrap();
        sc.validate(&file).unwrap();
        assert_eq!(sc.radio.ranges(4), vec![50.0, 50.0, 50.0, 900.0]);
        assert_eq!(sc.radio.range_scan, RangeScan::All);
        // The resolved scenario keeps them (and omits them when they are the defaults).
        assert_eq!(Scenario::parse(&sc.to_toml(), "r.toml").unwrap(), sc);
        assert!(!Scenario::default().to_toml().contains("sender_ranges"));
        let mut bad = sc.clone();
        bad.radio.sender_ranges[0].agent = 4;
        assert_eq!(
            bad.validate(&file).unwrap_err().key,
            "radio.sender_ranges[0].agent"
        );
        let mut bad = sc.clone();
        bad.radio.sender_ranges[0].comm_radius = -1.0;
        assert_eq!(
            bad.validate(&file).unwrap_err().key,
            "radio.sender_ranges[0].comm_radius"
        );
        let mut bad = sc.clone();
        bad.radio.sender_ranges.push(bad.radio.sender_ranges[0]);
        let e = bad.validate(&file).unwrap_err();
        assert_eq!(e.key, "radio.sender_ranges[1].agent");
        assert!(e.to_string().contains("already"), "{e}");
        let e = Scenario::parse(
            "[[radio.sender_ranges]]\nagent = 1\nrange = 3.0\n",
            "t.toml",
        )
        .unwrap_err();
        assert!(e.to_string().contains("range"), "{e}");
    }

    #[test]
    fn deserialisation_errors_name_the_key_path_and_the_line() {
        let e = Scenario::parse("[run]\nseed = 3\nrobots = -1\n", "t.toml").unwrap_err();
        assert_eq!(e.key, "run.robots");
        assert_eq!(e.source, "t.toml:3");
        assert!(e.to_string().contains("expected u32"), "{e}");
        let e = Scenario::parse(
            "[[arena.obstacles]]\nname = \"a\"\npoints = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]\n\n[[arena.obstacles]]\npoints = [[0.0, 0.0]]\n",
            "t.toml",
        )
        .unwrap_err();
        assert_eq!(e.key, "arena.obstacles[1]");
        assert_eq!(e.source, "t.toml:5");
        assert!(e.message.contains("missing field `name`"), "{e}");
        let e = Scenario::parse("[arena]\nwidth = \"wide\"\n", "t.toml").unwrap_err();
        assert_eq!(
            (e.key.as_str(), e.source.as_str()),
            ("arena.width", "t.toml:2")
        );
        let e = Scenario::parse("[radio]\n\ncomm_radiuss = 3\n", "t.toml").unwrap_err();
        assert_eq!(
            (e.key.as_str(), e.source.as_str()),
            ("radio.comm_radiuss", "t.toml:3")
        );
        // Syntax errors: the line, no key.
        let e = Scenario::parse("[run]\nrobots = = 3\n", "t.toml").unwrap_err();
        assert_eq!(e.source, "t.toml:2", "{e}");
        assert!(e.message.contains("not valid TOML"), "{e}");
    }

    #[test]
    fn validation_errors_name_the_line_in_the_file_or_in_the_default() {
        let dir = std::env::temp_dir().join(format!("swarm-keylines-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("loss.toml");
        std::fs::write(&path, "[run]\nrobots = 5\n\n[radio]\nloss = 1.5\n").unwrap();
        let sc = Scenario::load(&path).unwrap();
        let name = path.display().to_string();
        let e = sc.validate(&|_| name.clone()).unwrap_err();
        assert_eq!(e.key, "radio.loss");
        assert_eq!(e.source, format!("{name}:5"));
        // A key the file does not hold: its value came from the default, which is named.
        let mut sc = sc;
        sc.radio.loss = 0.0;
        sc.robot.v_max = -1.0;
        let e = sc.validate(&|_| name.clone()).unwrap_err();
        assert_eq!(e.key, "robot.v_max");
        assert!(
            e.source.starts_with("embedded default scenario:")
                && e.source.ends_with(&format!("(not set in {name})")),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn tick_hz_is_zero_or_a_period_that_fits_a_duration() {
        for hz in [1e-300, 1e-4, -1.0, f64::NAN, f64::INFINITY, 1e7] {
            let mut sc = Scenario::default();
            sc.runtime.tick_hz = hz;
            let e = sc.validate(&file).unwrap_err();
            assert_eq!(e.key, "runtime.tick_hz", "{hz}");
            assert!(e.to_string().contains("or 0: unpaced"), "{e}");
        }
        for hz in [0.0, MIN_TICK_HZ, 100.0, MAX_TICK_HZ] {
            let mut sc = Scenario::default();
            sc.runtime.tick_hz = hz;
            sc.validate(&file).unwrap();
            // The start of the last tick is a Duration.
            let _ = sc.runtime.tick_start(sc.run.max_ticks);
        }
    }

    #[test]
    fn resolved_scenario_round_trips_through_toml() {
        let sc = Scenario::default();
        let again = Scenario::parse(&sc.to_toml(), "resolved").unwrap();
        assert_eq!(sc, again);
    }

    /// The hand-written transports are retired (one transport per flow, iceoryx2): their
    /// keys are unknown, and the resolved scenario names no transport.
    #[test]
    fn the_retired_transport_keys_are_refused() {
        for text in [
            "[runtime]\nacts = \"cells\"\n",
            "[runtime]\nsense = \"ring\"\n",
            "[radio]\nair = \"ring\"\n",
        ] {
            assert!(Scenario::parse(text, "t.toml").is_err(), "{text}");
        }
        let resolved = Scenario::default().to_toml();
        for key in ["acts =", "sense =", "air ="] {
            assert!(!resolved.contains(key), "{key}");
        }
    }
}
