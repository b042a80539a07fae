//! Where a scenario key is written: the line of `arena.obstacles[3].points` in a TOML text, and
//! the `file:line` an error names for it.
//!
//! A scenario is the user's file merged over the embedded default, so a key the user's file
//! does not hold came from the default: its error names the default and the default's line.
//! Lines come from the TOML parser's spans (toml_edit, the parser of the `toml` crate).

use std::ops::Range;
use toml_edit::{ImDocument, Item, Value};

/// How errors name the embedded default scenario.
pub const DEFAULT_SOURCE: &str = "embedded default scenario";

/// One step of a key path: a table key or an array index.
#[derive(Debug, Clone, PartialEq)]
enum Seg {
    Key(String),
    Index(usize),
}

/// `arena.obstacles[3].points` -> [arena, obstacles, 3, points].
fn segments(key: &str) -> Vec<Seg> {
    let mut out = Vec::new();
    for part in key.split('.') {
        let (name, mut rest) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        if name == "\"\"" {
            // The empty key, written `""`.
            out.push(Seg::Key(String::new()));
        } else if !name.is_empty() {
            out.push(Seg::Key(name.to_string()));
        }
        while let Some(end) = rest.find(']') {
            if let Ok(i) = rest[1..end].parse() {
                out.push(Seg::Index(i));
            }
            rest = &rest[end + 1..];
        }
    }
    out
}

/// The span of the key `segs` below `item` (the key's own span where the text has one, else
/// its value's, else the nearest enclosing one's, `outer`), None when the text does not hold
/// the whole path (a table that merely contains it does not count).
fn span_of(item: &Item, segs: &[Seg], outer: Option<Range<usize>>) -> Option<Range<usize>> {
    let Some((first, rest)) = segs.split_first() else {
        return item.span().or(outer);
    };
    match first {
        Seg::Key(k) => {
            let (key, child) = item.as_table_like()?.get_key_value(k)?;
            // An implicit table (`[formation.kernels]` alone makes `formation`) has no span of
            // its own: its first written entry's.
            let here = key
                .span()
                .or_else(|| child.span())
                .or_else(|| first_span(child))
                .or(outer);
            if rest.is_empty() {
                here
            } else {
                span_of(child, rest, here)
            }
        }
        Seg::Index(i) => {
            let child = match item {
                Item::ArrayOfTables(a) => Item::Table(a.get(*i)?.clone()),
                Item::Value(Value::Array(a)) => Item::Value(a.get(*i)?.clone()),
                _ => return None,
            };
            let here = child.span().or(outer);
            if rest.is_empty() {
                here
            } else {
                span_of(&child, rest, here)
            }
        }
    }
}

/// The earliest span written below `item` (for tables the text never names itself).
fn first_span(item: &Item) -> Option<Range<usize>> {
    let t = item.as_table_like()?;
    t.iter()
        .filter_map(|(k, v)| {
            let (key, _) = t.get_key_value(k)?;
            key.span().or_else(|| v.span()).or_else(|| first_span(v))
        })
        .min_by_key(|s| s.start)
}

/// The dotted key written on line `line` (1-based) of `text`, for errors the parser reports
/// by line only (an integer beyond 64 bits): the last `[table]` header above it joined with
/// the line's `key =`. None when the line holds no `key =`.
pub fn key_at_line(text: &str, line: usize) -> Option<String> {
    let lines: Vec<&str> = text.lines().collect();
    let here = lines.get(line.checked_sub(1)?)?.trim();
    let (key, _) = here.split_once('=')?;
    let key = key.trim().trim_matches('"');
    if key.is_empty() || key.starts_with('[') || key.starts_with('#') {
        return None;
    }
    let table = lines[..line - 1].iter().rev().find_map(|l| {
        let l = l.trim();
        l.starts_with('[')
            .then(|| l.trim_matches(|c| c == '[' || c == ']').trim())
    });
    Some(match table {
        Some(t) if !t.is_empty() => format!("{t}.{key}"),
        _ => key.to_string(),
    })
}

/// 1-based line of byte `at` in `text`.
fn line_at(text: &str, at: usize) -> usize {
    text[..at.min(text.len())].matches('\n').count() + 1
}

/// The line of `key` (a dotted path with `[i]` indices) in the TOML `text`, if the text holds
/// that key (the whole path: a table that merely contains it does not count).
pub fn line_of(text: &str, key: &str) -> Option<usize> {
    let doc = ImDocument::parse(text).ok()?;
    let root = Item::Table(doc.as_table().clone());
    let segs = segments(key);
    if segs.is_empty() {
        return None;
    }
    span_of(&root, &segs, None).map(|s| line_at(text, s.start))
}

/// The line of the default's key, if it has it.
fn default_line(key: &str) -> Option<usize> {
    line_of(crate::scenario::DEFAULT_SCENARIO, key)
}

/// Names where `key` of a scenario read from `source` (whose text is `text`) is written:
/// `source:LINE` when the text holds it, else the default's line (`embedded default
/// scenario:LINE (not set in SOURCE)`), else `source` saying that neither sets it.
pub fn locate_in(source: &str, text: &str, key: &str) -> String {
    if key.is_empty() {
        return source.to_string();
    }
    if let Some(line) = line_of(text, key) {
        return format!("{source}:{line}");
    }
    match default_line(key) {
        Some(line) if source != DEFAULT_SOURCE => {
            format!("{DEFAULT_SOURCE}:{line} (not set in {source})")
        }
        Some(line) => format!("{DEFAULT_SOURCE}:{line}"),
        // Neither text writes it: the value is the program's own default, which is said
        // (rather than a line no text has).
        None if source == DEFAULT_SOURCE => format!("{source} (not set: built-in default)"),
        None => format!("{source} (not set there nor in the {DEFAULT_SOURCE}: built-in default)"),
    }
}

/// [`locate_in`] for a source named by validation: a flag (`--robots`) stays as it is, the
/// default is looked up in the embedded text, a file is read again (a source that is neither
/// a flag nor a readable file is returned as it is).
pub fn locate(source: &str, key: &str) -> String {
    if source.starts_with("--") || key.is_empty() {
        return source.to_string();
    }
    if source == DEFAULT_SOURCE {
        return locate_in(source, crate::scenario::DEFAULT_SCENARIO, key);
    }
    let path = std::path::Path::new(source);
    if path.extension().is_some_and(|e| e == "toml") {
        if let Ok(text) = std::fs::read_to_string(path) {
            return locate_in(source, &text, key);
        }
    }
    source.to_string()
}

/// The line of byte offset `at` in `text`, for parser errors that carry a span.
pub fn line_of_offset(text: &str, at: usize) -> usize {
    line_at(text, at)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "\
[run]
robots = 7

[arena]
width = 10.0

[[arena.obstacles]]
name = \"a\"
points = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]

[[arena.obstacles]]
name = \"b\"
points = [
  [5.0, 5.0],
  [6.0, 5.0],
]

[search.kernels.tpepso]
w = 0.5

[search]
kernels.bsoa.l_b = 50.0
";

    #[test]
    fn key_paths_split_into_keys_and_indices() {
        assert_eq!(
            segments("arena.obstacles[3].points"),
            vec![
                Seg::Key("arena".into()),
                Seg::Key("obstacles".into()),
                Seg::Index(3),
                Seg::Key("points".into())
            ]
        );
        assert_eq!(
            segments("faults.kill_at[1][0]"),
            vec![
                Seg::Key("faults".into()),
                Seg::Key("kill_at".into()),
                Seg::Index(1),
                Seg::Index(0)
            ]
        );
    }

    #[test]
    fn lines_of_keys_tables_arrays_and_dotted_keys() {
        assert_eq!(line_of(TEXT, "run.robots"), Some(2));
        assert_eq!(line_of(TEXT, "arena.width"), Some(5));
        assert_eq!(line_of(TEXT, "arena.obstacles[0].points"), Some(9));
        assert_eq!(line_of(TEXT, "arena.obstacles[1].name"), Some(12));
        assert_eq!(line_of(TEXT, "arena.obstacles[1].points[1]"), Some(15));
        assert_eq!(line_of(TEXT, "search.kernels.tpepso.w"), Some(19));
        assert_eq!(line_of(TEXT, "search.kernels.bsoa.l_b"), Some(22));
        // Not in the text (a table that contains it is not enough).
        assert_eq!(line_of(TEXT, "arena.height"), None);
        assert_eq!(line_of(TEXT, "arena.obstacles[2].points"), None);
        assert_eq!(line_of(TEXT, "radio.loss"), None);
    }

    #[test]
    fn implicit_tables_and_keys_of_a_line() {
        let text = "[run]\nrobots = 3\n\n[formation.kernels]\nx = 1\n";
        assert_eq!(line_of(text, "formation"), Some(4));
        assert_eq!(key_at_line(text, 2).as_deref(), Some("run.robots"));
        assert_eq!(key_at_line(text, 5).as_deref(), Some("formation.kernels.x"));
        assert_eq!(key_at_line(text, 4), None);
        assert_eq!(key_at_line("seed = 1\n", 1).as_deref(), Some("seed"));
        assert_eq!(line_of("a = 1\n\"\" = 2\n", "\"\""), Some(2));
    }

    #[test]
    fn a_key_the_file_does_not_hold_names_the_default() {
        assert_eq!(locate_in("x.toml", TEXT, "run.robots"), "x.toml:2");
        let d = locate_in("x.toml", TEXT, "radio.loss");
        assert!(
            d.starts_with("embedded default scenario:") && d.ends_with("(not set in x.toml)"),
            "{d}"
        );
        let line: usize = d
            .trim_start_matches("embedded default scenario:")
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        let text_line = crate::scenario::DEFAULT_SCENARIO
            .lines()
            .nth(line - 1)
            .unwrap();
        assert!(text_line.trim_start().starts_with("loss "), "{text_line}");
        assert_eq!(locate("--robots", "run.robots"), "--robots");
        assert_eq!(locate("a bench", "run.robots"), "a bench");
    }
}
