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

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Deserialize, Debug)]
    #[serde(deny_unknown_fields)]
    struct P {
        #[allow(dead_code)]
        gain: f64,
    }

    #[test]
    fn errors_name_the_users_file_the_key_path_and_the_line() {
        let dir = std::env::temp_dir().join(format!("swarm-params-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("s.toml");
        let text = "[run]\nrobots = 4\n\n[[agents]]\nrobots = [0]\ncommand = [\"a\"]\n\n\
                    [[agents]]\nrobots = [1]\ncommand = [\"b\"]\n[agents.params]\ngain = \"x\"\n";
        std::fs::write(&file, text).unwrap();
        let sc = crate::Scenario::load(&file).unwrap();
        assert_eq!(sc.agents[1].source.as_deref(), Some(file.to_str().unwrap()));
        let e = read::<P>(Some((1, &sc.agents[1])), "resolved.toml").unwrap_err();
        assert_eq!(e.key, "agents[1].params.gain");
        assert_eq!(e.source, format!("{}:12", file.display()));
        // A missing field is reported on the entry (it has no params table).
        let e = read::<P>(Some((0, &sc.agents[0])), "resolved.toml").unwrap_err();
        assert_eq!(e.key, "agents[0].params");
        assert!(e.message.contains("gain"), "{}", e.message);
        assert!(e.source.starts_with(file.to_str().unwrap()), "{}", e.source);
        // No entry: an empty table, the resolved file named.
        let e = read::<P>(None, "resolved.toml").unwrap_err();
        assert_eq!(e.source, "resolved.toml");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
