//! `swarm.Sense`: a robot's Sense frame for a Python `step`. It owns one `swarm::frames::Sense`
//! (the frame's fixed part and the used part of its lists are copied into it each tick, one
//! memcpy each) and exports it as a read-only buffer, so its lists are NumPy views of it with
//! no per-element conversion: `obstacles` (n x 2 float64), `nearby` and `entities` (structured
//! arrays whose dtypes mirror the `#[repr(C)]` records, `swarm._layout`).

use pyo3::exceptions::PyBufferError;
use pyo3::ffi;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyDict;
use std::mem::{offset_of, size_of};
use std::os::raw::{c_int, c_void};
use swarm::frames::{Entity, Nearby, Sense, SENSE_FIXED_BYTES};

/// The frame's layout for `swarm._layout` (which builds the NumPy dtypes from it): byte offsets
/// of the fields and lists, and the records' own field offsets and sizes.
pub fn layout(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("size", size_of::<Sense>())?;
    d.set_item("pos", offset_of!(Sense, pos))?;
    d.set_item("vel", offset_of!(Sense, vel))?;
    d.set_item("obstacle_points", offset_of!(Sense, obstacle_points))?;
    d.set_item("entities", offset_of!(Sense, entities))?;
    d.set_item("nearby", offset_of!(Sense, nearby))?;
    d.set_item(
        "nearby_fields",
        [
            ("robot", offset_of!(Nearby, robot)),
            ("pos", offset_of!(Nearby, pos)),
            ("vel", offset_of!(Nearby, vel)),
        ],
    )?;
    d.set_item("nearby_size", size_of::<Nearby>())?;
    d.set_item(
        "entity_fields",
        [
            ("id", offset_of!(Entity, id)),
            ("kind", offset_of!(Entity, kind)),
            ("flags", offset_of!(Entity, flags)),
            ("pos", offset_of!(Entity, pos)),
            ("value", offset_of!(Entity, value)),
        ],
    )?;
    d.set_item("entity_size", size_of::<Entity>())?;
    Ok(d)
}

/// What the array getters call, from `swarm._layout` (fetched once).
struct Views {
    frombuffer: Py<PyAny>,
    float64: Py<PyAny>,
    nearby: Py<PyAny>,
    entity: Py<PyAny>,
}

static VIEWS: PyOnceLock<Views> = PyOnceLock::new();

fn views(py: Python<'_>) -> PyResult<&Views> {
    VIEWS.get_or_try_init(py, || {
        let m = py.import("swarm._layout")?;
        Ok(Views {
            frombuffer: m.getattr("frombuffer")?.unbind(),
            float64: m.getattr("FLOAT64")?.unbind(),
            nearby: m.getattr("NEARBY")?.unbind(),
            entity: m.getattr("ENTITY")?.unbind(),
        })
    })
}

/// One tick's Sense frame (read-only; its arrays are views of it).
#[pyclass(name = "Sense", module = "swarm")]
pub struct PySense {
    frame: Box<Sense>,
}

impl Default for PySense {
    fn default() -> Self {
        Self::new()
    }
}

impl PySense {
    pub fn new() -> PySense {
        PySense {
            frame: Sense::zeroed(),
        }
    }

    /// Copies `s`: its fixed part and the used part of each list (the rest stays zero).
    pub fn fill(&mut self, s: &Sense) {
        let f = &mut *self.frame;
        // SAFETY: both are whole `Sense` frames (repr(C) plain data); the fixed part is the
        // first SENSE_FIXED_BYTES of each.
        unsafe {
            std::ptr::copy_nonoverlapping(
                s as *const Sense as *const u8,
                f as *mut Sense as *mut u8,
                SENSE_FIXED_BYTES,
            );
        }
        let (o, e, n) = (
            s.obstacle_points().len(),
            s.entities().len(),
            s.nearby().len(),
        );
        f.obstacle_points[..o].copy_from_slice(s.obstacle_points());
        f.entities[..e].copy_from_slice(s.entities());
        f.nearby[..n].copy_from_slice(s.nearby());
    }

    fn view<'py>(
        slf: &Bound<'py, Self>,
        dtype: &Py<PyAny>,
        count: usize,
        offset: usize,
    ) -> PyResult<Bound<'py, PyAny>> {
        let py = slf.py();
        let v = views(py)?;
        v.frombuffer
            .bind(py)
            .call1((slf, dtype.bind(py), count, offset))
    }
}

#[pymethods]
impl PySense {
    #[getter]
    fn tick(&self) -> u64 {
        self.frame.tick
    }
    #[getter]
    fn robot(&self) -> u32 {
        self.frame.robot
    }
    /// 0 running, 1 stopping (the run ends after this tick).
    #[getter]
    fn run_state(&self) -> u32 {
        self.frame.run_state
    }
    #[getter]
    fn heading(&self) -> f64 {
        self.frame.heading
    }
    /// Live robots in the run.
    #[getter]
    fn alive_robots(&self) -> u32 {
        self.frame.alive_robots
    }
    /// (x, y) as a tuple of floats (plain Python, no NumPy).
    #[getter]
    fn xy(&self) -> (f64, f64) {
        (self.frame.pos[0], self.frame.pos[1])
    }
    /// (vx, vy) as a tuple of floats.
    #[getter]
    fn vxy(&self) -> (f64, f64) {
        (self.frame.vel[0], self.frame.vel[1])
    }
    /// The obstacle points as a list of (x, y) tuples (plain Python; `obstacles` is the
    /// NumPy view).
    fn obstacle_list(&self) -> Vec<(f64, f64)> {
        self.frame
            .obstacle_points()
            .iter()
            .map(|p| (p[0], p[1]))
            .collect()
    }
    /// (x, y): float64 array of 2 (a view).
    #[getter]
    fn pos<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let f64s = &views(slf.py())?.float64;
        Self::view(slf, f64s, 2, offset_of!(Sense, pos))
    }
    /// (vx, vy): float64 array of 2 (a view).
    #[getter]
    fn vel<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let f64s = &views(slf.py())?.float64;
        Self::view(slf, f64s, 2, offset_of!(Sense, vel))
    }
    /// Obstacle, wall and dead-robot points in sensing range: float64, n x 2 (a view).
    #[getter]
    fn obstacles<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let n = slf.borrow().frame.obstacle_points().len();
        let f64s = &views(slf.py())?.float64;
        let flat = Self::view(slf, f64s, 2 * n, offset_of!(Sense, obstacle_points))?;
        flat.call_method1("reshape", (n, 2))
    }
    /// Robots this robot's own sensors see: structured array, fields `robot` (uint32), `pos`
    /// and `vel` (float64 x 2), a view.
    #[getter]
    fn nearby<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let n = slf.borrow().frame.nearby().len();
        let dt = &views(slf.py())?.nearby;
        Self::view(slf, dt, n, offset_of!(Sense, nearby))
    }
    /// Mission entities sensed: structured array, fields `id`, `kind`, `flags` (uint32),
    /// `pos` (float64 x 2), `value` (float64), a view.
    #[getter]
    fn entities<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let n = slf.borrow().frame.entities().len();
        let dt = &views(slf.py())?.entity;
        Self::view(slf, dt, n, offset_of!(Sense, entities))
    }

    fn __repr__(&self) -> String {
        let f = &self.frame;
        format!(
            "Sense(tick={}, robot={}, pos=({}, {}), nearby={}, entities={}, obstacles={})",
            f.tick,
            f.robot,
            f.pos[0],
            f.pos[1],
            f.nearby().len(),
            f.entities().len(),
            f.obstacle_points().len()
        )
    }

    /// The whole frame as a read-only buffer (the arrays above are views of it).
    unsafe fn __getbuffer__(
        slf: Bound<'_, Self>,
        view: *mut ffi::Py_buffer,
        flags: c_int,
    ) -> PyResult<()> {
        if flags & ffi::PyBUF_WRITABLE == ffi::PyBUF_WRITABLE {
            return Err(PyBufferError::new_err("a Sense frame is read-only"));
        }
        let ptr = &*slf.borrow().frame as *const Sense as *mut c_void;
        // SAFETY: the frame is a Box that lives as long as this object, which the buffer holds
        // a reference to (PyBuffer_FillInfo takes one); it is only written in place when no
        // other reference exists (`PyBehaviour`), so never while a view of it lives.
        let rc = unsafe {
            ffi::PyBuffer_FillInfo(
                view,
                slf.as_ptr(),
                ptr,
                size_of::<Sense>() as ffi::Py_ssize_t,
                1,
                flags,
            )
        };
        if rc == -1 {
            return Err(PyErr::fetch(slf.py()));
        }
        Ok(())
    }
}
