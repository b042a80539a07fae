//! A user program's own parameters: its `[[agents]]` entry's `params` table, deserialised into
//! the program's type with errors that name the file, the key path (`agents[1].params.gain`)
//! and the line, as the built-in sections' errors do.

use crate::scenario::{AgentEntry, ConfigError};
use serde::de::DeserializeOwned;

/// Deserialises `entry.params` (`entry` is `agents[index]`; no entry: an empty table, so a
/// type whose fields all have defaults still reads). `resolved` is the scenario file the agent
/// was given; errors name the entry's own source file when it is readable (the user's file),
/// else `resolved`.
pub fn read<T: DeserializeOwned>(
    entry: Option<(usize, &AgentEntry)>,
    resolved: &str,
) -> Result<T, ConfigError> {
    let (index, table) = match entry {
        Some((i, e)) => (Some(i), e.params.clone()),
        None => (None, toml::Table::new()),
    };
    serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(
        |e: serde_path_to_error::Error<toml::de::Error>| {
            let path = e.path().to_string();
            let base = match index {
                Some(i) => format!("agents[{i}].params"),
                None => "params (this robot has no [[agents]] entry)".to_string(),
            };
            let key = if path == "." {
                base.clone()
            } else {
                format!("{base}.{path}")
            };
            let source = match (index, entry.and_then(|(_, e)| e.source.as_deref())) {
                (Some(_), Some(s)) if std::fs::metadata(s).is_ok() => s,
                _ => resolved,
            };
            ConfigError {
                source: locate(source, &key),
                key,
                message: e.inner().message().trim().to_string(),
            }
        },
    )
}

/// `source:LINE` of `key`, or of the nearest enclosing key the file holds (a missing field is
/// reported on its table: `agents[1].params`, or the entry itself when it has no params).
fn locate(source: &str, key: &str) -> String {
    let Ok(text) = std::fs::read_to_string(source) else {
        return source.to_string();
    };
    let mut k = key;
    loop {
        if let Some(line) = crate::key_lines::line_of(&text, k) {
            return format!("{source}:{line}");
        }
        match k.rfind('.') {
            Some(i) => k = &k[..i],
            None => return source.to_string(),
        }
    }
}
