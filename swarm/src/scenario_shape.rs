//! What any scenario text may hold before its keys are read (issue 37): how big the file is,
//! how long a list, a string or a key may be, and whether it is a scenario at all (an
//! experiment file given to `up`). Each refusal names the key path and its line, and never
//! echoes a huge value back.

use crate::scenario::ConfigError;

/// Largest scenario file read (bytes): the biggest committed scenario is 12 KB and a
/// 4,096-robot hunt table about 1 MB; `--scenario /dev/zero` stops here instead of reading
/// until the OOM killer.
pub const MAX_SCENARIO_BYTES: u64 = 4 << 20;

/// Most entries of any one list (array or array of tables) a scenario may hold. The longest a
/// run needs are one per robot (`formation.template`, `[[hunt.robots]]`: MAX_ROBOTS = 4,096)
/// and the kills a resolved chaos run lists; every list also has its own bound where its
/// length costs work (`Scenario::validate`, the behaviours' and missions' checks).
pub const MAX_LIST_ENTRIES: usize = 100_000;

/// Longest string value (bytes): names, modes and model names are a few dozen bytes.
pub const MAX_STRING_BYTES: usize = 256;

/// Longest key (bytes): the longest key of a scenario is about 40 bytes.
pub const MAX_KEY_BYTES: usize = 64;

/// Most characters of a user's string or key an error message shows.
pub const SHOWN_CHARS: usize = 40;

/// Top-level keys of an experiment file (`orchestrator experiment`, orchestrator/src/
/// experiment*.rs): a scenario has none of them.
pub const EXPERIMENT_KEYS: &[&str] = &["kind", "scenario"];

/// `s` as an error shows it: whole when short, else its first [`SHOWN_CHARS`] characters and
/// its length.
pub fn shown(s: &str) -> String {
    if s.chars().count() <= SHOWN_CHARS {
        format!("{s:?}")
    } else {
        let head: String = s.chars().take(SHOWN_CHARS).collect();
        format!("{head:?}... ({} bytes)", s.len())
    }
}

/// Reads at most [`MAX_SCENARIO_BYTES`] of `path` (a longer file, or a device that never
/// ends, is refused).
pub fn read_bounded(path: &std::path::Path) -> Result<String, String> {
    use std::io::Read;
    let f = std::fs::File::open(path).map_err(|e| format!("cannot read scenario file: {e}"))?;
    if f.metadata().is_ok_and(|m| m.is_dir()) {
        return Err("cannot read scenario file: it is a directory".into());
    }
    let mut bytes = Vec::new();
    f.take(MAX_SCENARIO_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("cannot read scenario file: {e}"))?;
    if bytes.len() as u64 > MAX_SCENARIO_BYTES {
        return Err(format!(
            "cannot read scenario file: it is larger than {} MiB (MAX_SCENARIO_BYTES); a \
             scenario is a TOML file of a few KB",
            MAX_SCENARIO_BYTES >> 20
        ));
    }
    String::from_utf8(bytes).map_err(|e| {
        format!(
            "cannot read scenario file: not UTF-8 text (invalid byte at offset {})",
            e.utf8_error().valid_up_to()
        )
    })
}

/// Checks the user's table `t` (the text `text` read from `source`): no experiment keys, no
/// list, string or key over its bound.
pub fn check(t: &toml::Table, text: &str, source: &str) -> Result<(), ConfigError> {
    let err = |key: &str, message: String| ConfigError {
        source: crate::key_lines::locate_in(source, text, key),
        key: key.to_string(),
        message,
    };
    if let Some(k) = EXPERIMENT_KEYS.iter().find(|k| t.contains_key(**k)) {
        return Err(err(
            k,
            format!(
                "is a key of an experiment file, not of a scenario: run it with \
                 `orchestrator experiment {source}` (`orchestrator up --scenario` takes a \
                 scenario: [run], [arena], ... sections)"
            ),
        ));
    }
    walk_table(t, "", &err)
}

type Err<'a> = &'a dyn Fn(&str, String) -> ConfigError;

fn join(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

fn walk_table(t: &toml::Table, path: &str, err: Err) -> Result<(), ConfigError> {
    for (k, v) in t {
        if k.is_empty() {
            return Err(err(
                &join(path, "\"\""),
                "is an empty key: no scenario key is empty".into(),
            ));
        }
        if k.len() > MAX_KEY_BYTES {
            let at = if path.is_empty() {
                "the top level"
            } else {
                path
            };
            return Err(err(
                path,
                format!(
                    "holds a key of {} bytes ({}): keys are at most {MAX_KEY_BYTES} bytes \
                     (MAX_KEY_BYTES); no scenario key is that long (in {at})",
                    k.len(),
                    shown(k)
                ),
            ));
        }
        walk(v, &join(path, k), err)?;
    }
    Ok(())
}

fn walk(v: &toml::Value, path: &str, err: Err) -> Result<(), ConfigError> {
    match v {
        toml::Value::String(s) if s.len() > MAX_STRING_BYTES => Err(err(
            path,
            format!(
                "= {} is too long: strings are at most {MAX_STRING_BYTES} bytes \
                 (MAX_STRING_BYTES)",
                shown(s)
            ),
        )),
        toml::Value::Array(a) => {
            if a.len() > MAX_LIST_ENTRIES {
                return Err(err(
                    path,
                    format!(
                        "has {} entries: lists are at most {MAX_LIST_ENTRIES} entries \
                         (MAX_LIST_ENTRIES)",
                        a.len()
                    ),
                ));
            }
            for (i, x) in a.iter().enumerate() {
                walk(x, &format!("{path}[{i}]"), err)?;
            }
            Ok(())
        }
        toml::Value::Table(t) => walk_table(t, path, err),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refused(text: &str) -> ConfigError {
        let t: toml::Table = text.parse().unwrap();
        check(&t, text, "t.toml").unwrap_err()
    }

    #[test]
    fn long_lists_strings_and_keys_are_refused_with_their_key_and_line() {
        let text = format!(
            "[run]\nseed = 1\n\n[[arena.discs]]\nname = \"a\"\ncentre = [{}]\n",
            vec!["1.0"; MAX_LIST_ENTRIES + 1].join(", ")
        );
        let e = refused(&text);
        assert_eq!(
            (e.key.as_str(), e.source.as_str()),
            ("arena.discs[0].centre", "t.toml:6")
        );
        assert!(e.message.contains("100001 entries"), "{e}");
        let text = format!("[run]\nbehaviour = \"{}\"\n", "x".repeat(1 << 20));
        let e = refused(&text);
        assert_eq!(
            (e.key.as_str(), e.source.as_str()),
            ("run.behaviour", "t.toml:2")
        );
        assert!(e.message.len() < 200, "the string is not echoed whole: {e}");
        assert!(e.message.contains("1048576 bytes"), "{e}");
        let text = format!("[radio]\n{} = 1\n", "k".repeat(5000));
        let e = refused(&text);
        assert_eq!(e.key, "radio");
        assert!(e.message.len() < 300, "{e}");
        let t: toml::Table = "[run]\nrobots = 3\n".parse().unwrap();
        assert!(check(&t, "[run]\nrobots = 3\n", "t.toml").is_ok());
    }

    #[test]
    fn an_experiment_file_is_sent_to_orchestrator_experiment() {
        let e = refused("# an experiment\nkind = \"cbca\"\nseeds = 3\n");
        assert_eq!((e.key.as_str(), e.source.as_str()), ("kind", "t.toml:2"));
        assert!(e.message.contains("orchestrator experiment t.toml"), "{e}");
    }

    #[test]
    fn shown_strings_are_cut() {
        assert_eq!(shown("BT"), "\"BT\"");
        let s = shown(&"é".repeat(1000));
        assert!(
            s.ends_with("... (2000 bytes)") && s.chars().count() < 70,
            "{s}"
        );
    }

    #[test]
    fn endless_and_huge_files_are_refused_after_the_bound() {
        let e = read_bounded(std::path::Path::new("/dev/zero")).unwrap_err();
        assert!(e.contains("larger than 4 MiB"), "{e}");
        let e = read_bounded(std::path::Path::new("/")).unwrap_err();
        assert!(e.contains("directory"), "{e}");
    }
}
