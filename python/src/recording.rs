//! `read_recording(path)`: a `recording.bin` decoded by `swarm::recording` (the reader the
//! orchestrator's exports and viewer use), handed to Python as flat little columns: the
//! per-robot arrays as native-endian bytes that `swarm.Recording` views with NumPy, the events
//! and radio counters as lists for pandas.

use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};
use swarm::radio::RadioCounters;
use swarm::recording::TickRecord;

/// The radio counters' fields, in the order of `summary.json`'s `messages`.
const RADIO_FIELDS: [&str; 9] = [
    "offered",
    "delivered",
    "dropped_range",
    "dropped_occluded",
    "dropped_bandwidth",
    "dropped_loss",
    "malformed",
    "receiver_dead",
    "in_flight",
];

fn radio_row(c: &RadioCounters) -> [u64; 9] {
    [
        c.offered,
        c.delivered,
        c.dropped_range,
        c.dropped_occluded,
        c.dropped_bandwidth,
        c.dropped_loss,
        c.malformed,
        c.receiver_dead,
        c.in_flight,
    ]
}

/// Bytes of a slice of plain numbers, in the machine's byte order.
fn bytes_of<T: Copy>(py: Python<'_>, v: &[T]) -> Py<PyBytes> {
    // SAFETY: T is a plain number type (u64, f64, u8): every byte of it is initialised.
    let raw =
        unsafe { std::slice::from_raw_parts(v.as_ptr() as *const u8, std::mem::size_of_val(v)) };
    PyBytes::new(py, raw).unbind()
}

/// A row per tick, a column per robot: `field` of each robot (0 where a tick lists fewer).
fn per_robot<T: Copy + Default>(
    ticks: &[TickRecord],
    robots: usize,
    field: impl Fn(&TickRecord) -> &[T],
) -> Vec<T> {
    let mut out = Vec::with_capacity(ticks.len() * robots);
    for t in ticks {
        let row = field(t);
        out.extend((0..robots).map(|i| row.get(i).copied().unwrap_or_default()));
    }
    out
}

/// Reads `path` (a `recording.bin`). Returns a dict: `version`, `robots`, `seed`, `scenario`
/// (TOML text); `ticks` (u64), `poses` (f64, ticks x robots x 3), `alive` and `states` (u8,
/// ticks x robots) as bytes; `events` (a dict of columns); `radio_fields` and `radio`,
/// `radio_bytes` (u64 bytes, ticks x fields).
#[pyfunction]
pub fn read_recording(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Py<PyDict>> {
    let (header, ticks) = py
        .detach(|| std::fs::File::open(&path).and_then(swarm::recording::read_recording))
        .map_err(|e| PyOSError::new_err(format!("{}: {e}", path.display())))?;
    let n = header.robots as usize;
    let d = PyDict::new(py);
    d.set_item("version", header.version)?;
    d.set_item("robots", header.robots)?;
    d.set_item("seed", header.seed)?;
    d.set_item("scenario", &header.scenario)?;
    let tick_ids: Vec<u64> = ticks.iter().map(|t| t.tick).collect();
    d.set_item("ticks", bytes_of(py, &tick_ids))?;
    let poses = per_robot(&ticks, n, |t| &t.poses);
    d.set_item("poses", bytes_of(py, &poses))?;
    d.set_item("alive", bytes_of(py, &per_robot(&ticks, n, |t| &t.alive)))?;
    d.set_item("states", bytes_of(py, &per_robot(&ticks, n, |t| &t.states)))?;

    let (mut tick, mut name, mut robot, mut entity, mut detail) =
        (vec![], vec![], vec![], vec![], vec![]);
    for t in &ticks {
        for e in &t.events {
            tick.push(t.tick);
            name.push(e.name());
            robot.push(e.robot());
            entity.push(e.entity());
            detail.push(e.detail());
        }
    }
    let ev = PyDict::new(py);
    ev.set_item("tick", tick)?;
    ev.set_item("event", name)?;
    ev.set_item("robot", robot)?;
    ev.set_item("entity", entity)?;
    ev.set_item("detail", detail)?;
    d.set_item("events", ev)?;

    d.set_item("radio_fields", PyList::new(py, RADIO_FIELDS)?)?;
    let radio: Vec<u64> = ticks.iter().flat_map(|t| radio_row(&t.radio)).collect();
    d.set_item("radio", bytes_of(py, &radio))?;
    let radio_bytes: Vec<u64> = ticks
        .iter()
        .flat_map(|t| radio_row(&t.radio_bytes))
        .collect();
    d.set_item("radio_bytes", bytes_of(py, &radio_bytes))?;
    Ok(d.unbind())
}
