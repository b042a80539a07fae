//! `swarm._native`: the Rust side of the `swarm` Python package. It reads recordings with the
//! runtime's own reader ([`recording`]) and runs Python behaviours inside the runtime's own
//! agent loop ([`agent`]); the Python modules in `python/swarm/` build the user's API on it.

use pyo3::prelude::*;

mod recording;

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(recording::read_recording, m)?)?;
    Ok(())
}
