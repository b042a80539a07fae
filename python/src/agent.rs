//! `run_agent(argv, make)`: a Python behaviour run by the runtime's own agent loop
//! (`swarm::agent::Agent::run`: attach, barrier, transport, restart, ack deadline), so a Python
//! robot speaks the protocol exactly as a Rust one. The GIL is released while the loop waits
//! on the barrier and taken for each `step`.
//!
//! Messages are `bytes` at the boundary: the behaviour's `Msg` is `Vec<u8>`, which bincode puts
//! on the air as a varint length and the raw bytes. A Rust behaviour talks to Python ones with
//! `type Msg = Vec<u8>` and both sides agree on what the bytes hold.

use crate::sense::PySense;
use pyo3::prelude::*;
use pyo3::pybacked::PyBackedBytes;
use pyo3::types::{PyBytes, PyList};
use rand::RngCore;
use swarm::agent::{Agent, AgentError, EXIT_BAD_INPUT};
use swarm::frames::{BROADCAST, MAX_SENT};
use swarm::{Behaviour, Command, Outbox, Received, Sense};

/// Exit code of a Python agent whose `step` raised (or returned something that is no
/// command): the robot ends as a fault; the traceback is on its stderr (its log).
pub use swarm::agent::EXIT_BEHAVIOUR_FAULT;
/// 64-bit words drawn from the robot's user stream 0 (`Agent::rng(0)`) to seed the behaviour's
/// NumPy generator (`np.random.SeedSequence(words)`).
const SEED_WORDS: usize = 4;

/// What the behaviour's constructor is handed (`swarm.Agent` wraps it).
#[pyclass(name = "AgentInfo", module = "swarm", frozen)]
pub struct PyAgentInfo {
    #[pyo3(get)]
    robot: u32,
    #[pyo3(get)]
    robots: u32,
    #[pyo3(get)]
    seed: u64,
    #[pyo3(get)]
    run_id: String,
    /// The resolved scenario (TOML text).
    #[pyo3(get)]
    scenario_toml: String,
    /// This robot's `[[agents]]` params (JSON text; `{}` without an entry).
    #[pyo3(get)]
    params_json: String,
    /// [`SEED_WORDS`] words of this robot's seeded user stream 0.
    #[pyo3(get)]
    rng_words: Vec<u64>,
}

impl PyAgentInfo {
    fn of(a: &Agent) -> Result<PyAgentInfo, String> {
        let params: serde_json::Value = a.params().map_err(|e| e.to_string())?;
        let mut rng = a.rng(0);
        Ok(PyAgentInfo {
            robot: a.robot(),
            robots: a.scenario().run.robots,
            seed: a.scenario().run.seed,
            run_id: a.run_id().to_string(),
            scenario_toml: toml::to_string(a.scenario()).map_err(|e| e.to_string())?,
            params_json: params.to_string(),
            rng_words: (0..SEED_WORDS).map(|_| rng.next_u64()).collect(),
        })
    }
}

/// A delivered message.
#[pyclass(name = "Message", module = "swarm", frozen)]
pub struct PyMessage {
    /// The sender's robot id.
    #[pyo3(get)]
    sender: u32,
    /// The tick it was sent at.
    #[pyo3(get)]
    tick: u64,
    #[pyo3(get)]
    seq: u32,
    /// Where the sender was when it sent it.
    #[pyo3(get)]
    sender_pos: (f64, f64),
    /// Sent to this robot alone (not a broadcast).
    #[pyo3(get)]
    unicast: bool,
    #[pyo3(get)]
    data: Py<PyBytes>,
}

#[pymethods]
impl PyMessage {
    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "Message(sender={}, tick={}, {} bytes)",
            self.sender,
            self.tick,
            self.data.bind(py).as_bytes().len()
        )
    }
}

/// What a `step` sends: `out.broadcast(data)`, `out.send(robot, data)` (bytes).
#[pyclass(name = "Outbox", module = "swarm")]
pub struct PyOutbox {
    msgs: Vec<(u32, PyBackedBytes)>,
    /// The runtime's per-tick limit (radio.max_messages_per_tick, at most MAX_SENT).
    limit: usize,
}

#[pymethods]
impl PyOutbox {
    /// Queues `data` for every robot in range. False once the per-tick limit is reached.
    fn broadcast(&mut self, data: PyBackedBytes) -> bool {
        self.push(BROADCAST, data)
    }
    /// Queues `data` for robot `to` (still subject to range and loss). False past the limit.
    fn send(&mut self, to: u32, data: PyBackedBytes) -> bool {
        self.push(to, data)
    }
    fn __len__(&self) -> usize {
        self.msgs.len()
    }
}

impl PyOutbox {
    /// Every message is handed on, so the runtime counts the refused ones as for Rust.
    fn push(&mut self, to: u32, data: PyBackedBytes) -> bool {
        self.msgs.push((to, data));
        self.msgs.len() <= self.limit
    }
}

/// A command with what a robot reports to the mission: `swarm.Command(cmd=(a, b),
/// report=(r0, r1, r2, r3), events=flags)`. A `step` may also return `(a, b)` or None (idle).
#[pyclass(name = "Command", module = "swarm")]
#[derive(Clone)]
pub struct PyCommand {
    #[pyo3(get, set)]
    cmd: (f64, f64),
    #[pyo3(get, set)]
    report: (f64, f64, f64, f64),
    #[pyo3(get, set)]
    events: u32,
}

#[pymethods]
impl PyCommand {
    #[new]
    #[pyo3(signature = (cmd = (0.0, 0.0), report = (0.0, 0.0, 0.0, 0.0), events = 0))]
    fn new(cmd: (f64, f64), report: (f64, f64, f64, f64), events: u32) -> Self {
        PyCommand {
            cmd,
            report,
            events,
        }
    }
}

/// `step`'s return value as a command.
fn command_of(ret: &Bound<'_, PyAny>) -> PyResult<Command> {
    if ret.is_none() {
        return Ok(Command::default());
    }
    if let Ok(c) = ret.cast::<PyCommand>() {
        let c = c.borrow();
        return Ok(Command {
            cmd: [c.cmd.0, c.cmd.1],
            events: c.events,
            report: [c.report.0, c.report.1, c.report.2, c.report.3],
        });
    }
    match ret.extract::<Vec<f64>>() {
        Ok(v) if v.len() == 2 => Ok(Command {
            cmd: [v[0], v[1]],
            ..Command::default()
        }),
        _ => Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "step returned {}: allowed (a, b) (two numbers), swarm.Command or None",
            ret.repr()?
        ))),
    }
}

/// A Python object with `step(sense, inbox, out)` as a [`Behaviour`].
struct PyBehaviour {
    robot: u32,
    step: Py<PyAny>,
    sense: Py<PySense>,
    out: Py<PyOutbox>,
}

impl PyBehaviour {
    fn call(
        &mut self,
        py: Python<'_>,
        sense: &Sense,
        inbox: &[&Received<Vec<u8>>],
        out: &mut Outbox<Vec<u8>>,
    ) -> PyResult<Command> {
        // The frame object is written in place unless the behaviour kept it (or a view of
        // it) from an earlier tick: then that one stays as it was and a new one is made.
        // SAFETY: a live object's reference count, read with the GIL held.
        if unsafe { pyo3::ffi::Py_REFCNT(self.sense.as_ptr()) } > 1 {
            self.sense = Py::new(py, PySense::new())?;
        }
        self.sense.borrow_mut(py).fill(sense);
        let msgs = PyList::empty(py);
        for r in inbox {
            let m = PyMessage {
                sender: r.from,
                tick: r.tick,
                seq: r.seq,
                sender_pos: (r.sender_pos[0], r.sender_pos[1]),
                unicast: r.unicast,
                data: PyBytes::new(py, &r.msg).unbind(),
            };
            msgs.append(Py::new(py, m)?)?;
        }
        let ret = self
            .step
            .bind(py)
            .call1((self.sense.bind(py), msgs, self.out.bind(py)));
        let queued = std::mem::take(&mut self.out.borrow_mut(py).msgs);
        let cmd = command_of(&ret?)?;
        for (to, data) in queued {
            if to == BROADCAST {
                out.broadcast(data.to_vec());
            } else {
                out.send(to, data.to_vec());
            }
        }
        Ok(cmd)
    }

    /// The behaviour failed: its traceback goes to stderr (the robot's log) and the process
    /// ends with [`EXIT_BEHAVIOUR_FAULT`]: the runtime takes the robot for dead (a fault, as
    /// a crash is), restarts it under `on_fault = "restart"`, and the run goes on.
    fn fault(&self, py: Python<'_>, e: PyErr) -> ! {
        eprintln!(
            "agent {}: the Python behaviour's step raised; the robot's agent ends (a fault):",
            self.robot
        );
        e.print(py);
        if let Ok(sys) = py.import("sys") {
            for stream in ["stdout", "stderr"] {
                let _ = sys.getattr(stream).and_then(|s| s.call_method0("flush"));
            }
        }
        std::process::exit(EXIT_BEHAVIOUR_FAULT)
    }
}

impl Behaviour for PyBehaviour {
    type Msg = Vec<u8>;
    fn step_refs(
        &mut self,
        sense: &Sense,
        inbox: &[&Received<Vec<u8>>],
        out: &mut Outbox<Vec<u8>>,
    ) -> Command {
        Python::attach(|py| match self.call(py, sense, inbox, out) {
            Ok(c) => c,
            Err(e) => self.fault(py, e),
        })
    }
}

/// Runs robot `--robot I` of a run (`argv`: the agent arguments the orchestrator passes) with
/// the behaviour `make(info)` returns. Returns the agent's exit code (`swarm.run` exits with
/// it); bad arguments, scenario, params or a constructor that raises: 2, the message on stderr.
#[pyfunction]
pub fn run_agent(py: Python<'_>, argv: Vec<String>, make: Bound<'_, PyAny>) -> PyResult<i32> {
    let agent = match Agent::from_args(argv) {
        Ok(a) => a,
        Err(AgentError::Args(e)) => {
            let _ = e.print();
            return Ok(e.exit_code());
        }
        Err(e) => {
            eprintln!("agent: {e}");
            return Ok(e.exit_code());
        }
    };
    let robot = agent.robot();
    let info = match PyAgentInfo::of(&agent) {
        Ok(i) => i,
        Err(e) => {
            eprintln!("agent {robot}: {e}");
            return Ok(EXIT_BAD_INPUT);
        }
    };
    let step = make
        .call1((info,))
        .and_then(|obj| obj.getattr("step"))
        .map(Bound::unbind);
    let step = match step {
        Ok(s) => s,
        Err(e) => {
            eprintln!("agent {robot}: the Python behaviour could not be made:");
            e.print(py);
            return Ok(EXIT_BAD_INPUT);
        }
    };
    let limit = (agent.scenario().radio.max_messages_per_tick as usize).min(MAX_SENT);
    let behaviour = PyBehaviour {
        robot,
        step,
        sense: Py::new(py, PySense::new())?,
        out: Py::new(
            py,
            PyOutbox {
                msgs: Vec::new(),
                limit,
            },
        )?,
    };
    match py.detach(move || agent.run(behaviour)) {
        Ok(code) => Ok(code),
        Err(e) => {
            eprintln!("agent {robot}: {e}");
            Ok(e.exit_code())
        }
    }
}
