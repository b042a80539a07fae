//! `orchestrator experiment FILE`: the file's top-level `kind` picks the experiment (none: a
//! search grid); every kind takes the same flags and writes only under `--out`
//! (experiment_runner.rs, shared), each its own tables as a report over its rows.

#[path = "experiment_runner.rs"]
pub mod runner;
#[path = "experiment_search.rs"]
mod search;
#[path = "experiment_variant.rs"]
mod variant;

pub use runner::ExperimentArgs;
pub use variant::Variant;

/// The kinds an experiment file's `kind` may name.
const KINDS: [&str; 4] = ["search", "formation", "hunt", "cbca"];

pub fn experiment(a: ExperimentArgs) -> i32 {
    match run(a) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            2
        }
    }
}

/// The experiment file's top-level `kind` (None: no `kind` key, a search grid).
fn kind_of(path: &std::path::Path) -> Result<Option<String>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let t: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| format!("{}: {e}", path.display()))?;
    match t.get("kind") {
        None => Ok(None),
        Some(toml::Value::String(k)) if KINDS.contains(&k.as_str()) => Ok(Some(k.clone())),
        Some(k) => Err(format!(
            "{}: kind = {k}: allowed {}",
            path.display(),
            KINDS.map(|k| format!("{k:?}")).join(", ")
        )),
    }
}

/// Mean and sample standard deviation (0 for fewer than two values).
pub(crate) fn mean_sd(v: &[f64]) -> (f64, f64) {
    let n = v.len().max(1) as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (m, var.sqrt())
}

fn run(a: ExperimentArgs) -> Result<i32, String> {
    let kind = kind_of(&a.file)?;
    let ctx = runner::Context::new(&a)?;
    let report = match kind.as_deref() {
        Some("formation") => crate::experiment_formation::run(&ctx)?,
        Some("hunt") => crate::experiment_hunt::run(&ctx)?,
        Some("cbca") => crate::experiment_cbca::run(&ctx)?,
        _ => search::run(&ctx)?,
    };
    runner::write_results(&ctx, kind.as_deref().unwrap_or("search"), &report)
        .map_err(|e| e.to_string())?;
    Ok(if report.failed { 1 } else { 0 })
}
