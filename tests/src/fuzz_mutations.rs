//! The structural mutations of the fuzz generator (issue 37): what a user's file can get
//! wrong beyond one bad value. On the parsed table: a list grown huge, a section of another
//! behaviour, a key moved to the wrong table, a unicode key. On the written text: a key or a
//! table written twice, an integer beyond 64 bits. Each returns what it did, for the report.

use rand::seq::SliceRandom;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use toml::{Table, Value};

/// Lengths a grown list takes: over the behaviours' own bounds (64 discs), over the
/// structural bound of any list (100,000 entries), and a plausible mid size.
const HUGE_LENGTHS: &[usize] = &[65, 1_000, 10_000, 100_001];

/// Sections of a behaviour or mission, each with one key, that a case adds to a base which
/// may not use them (a roam run with `[formation] epsilon = -1` was accepted).
const FOREIGN_SECTIONS: &[(&str, &str, f64)] = &[
    ("formation", "epsilon", -1.0),
    ("formation", "epsilon", 0.1),
    ("hunt", "params", 0.0),
    ("cbca", "params", 0.0),
    ("search", "signal_m", 2.0),
    ("roam", "l_r", 3.0),
];

/// Keys and strings with characters a parser or a message may trip on.
pub const UNICODE: &[&str] = &[
    "épsilon",
    "ロボット",
    "\u{202e}reversed",
    "emoji🤖",
    "zero\u{200b}width",
    "",
];

/// A huge string (1 MB): a message must not echo it whole.
pub fn huge_string() -> String {
    "x".repeat(1 << 20)
}

/// Grows a list of `doc` (an array leaf, or `arena.discs` with generated discs) to a huge
/// length.
pub fn huge_list(rng: &mut ChaCha8Rng, doc: &mut Table) -> String {
    let n = *HUGE_LENGTHS.choose(rng).unwrap();
    if rng.gen_bool(0.5) {
        let discs: Vec<Value> = (0..n)
            .map(|k| {
                let mut d = Table::new();
                d.insert("name".into(), Value::String(format!("d{k}")));
                let (x, y) = (1.0 + (k % 20) as f64, 1.0 + (k / 20 % 20) as f64);
                d.insert(
                    "centre".into(),
                    Value::Array(vec![Value::Float(x), Value::Float(y)]),
                );
                d.insert("radius".into(), Value::Float(0.1));
                Value::Table(d)
            })
            .collect();
        let arena = doc
            .entry("arena")
            .or_insert_with(|| Value::Table(Table::new()));
        if let Value::Table(a) = arena {
            a.insert("discs".into(), Value::Array(discs));
        }
        return format!("arena.discs x {n}");
    }
    let mut arrays = Vec::new();
    find_arrays(&Value::Table(doc.clone()), String::new(), &mut arrays);
    let Some(path) = arrays.choose(rng).cloned() else {
        return "no list to grow".into();
    };
    if let Some(Value::Array(a)) = at_dotted(doc, &path) {
        let first = a[0].clone();
        a.resize(n, first);
    }
    format!("{path} x {n}")
}

fn find_arrays(v: &Value, path: String, out: &mut Vec<String>) {
    match v {
        Value::Table(t) => {
            for (k, c) in t {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                find_arrays(c, p, out);
            }
        }
        Value::Array(a) if !a.is_empty() => out.push(path),
        _ => {}
    }
}

/// The value at a dotted path of tables (no indices).
fn at_dotted<'a>(t: &'a mut Table, path: &str) -> Option<&'a mut Value> {
    let mut parts = path.split('.');
    let mut cur = t.get_mut(parts.next()?)?;
    for p in parts {
        cur = match cur {
            Value::Table(t) => t.get_mut(p)?,
            _ => return None,
        };
    }
    Some(cur)
}

/// Adds a section of some behaviour or mission (maybe one the base's run does not use).
pub fn foreign_section(rng: &mut ChaCha8Rng, doc: &mut Table) -> String {
    let (section, key, v) = *FOREIGN_SECTIONS.choose(rng).unwrap();
    let value = if key == "params" {
        // A sub-table with one tunable.
        let mut p = Table::new();
        let (k, x) = if section == "hunt" {
            ("encirclement_slowdown", 2.0)
        } else {
            ("max_tasks", 3.0)
        };
        p.insert(k.into(), Value::Float(x));
        Value::Table(p)
    } else {
        Value::Float(v)
    };
    let s = doc
        .entry(section)
        .or_insert_with(|| Value::Table(Table::new()));
    if let Value::Table(t) = s {
        t.insert(key.into(), value);
    }
    format!("foreign section [{section}] {key}")
}

/// Moves one key of a section into another section (a key in the wrong table).
pub fn wrong_table(rng: &mut ChaCha8Rng, doc: &mut Table) -> String {
    let sections: Vec<String> = doc
        .iter()
        .filter(|(_, v)| v.is_table())
        .map(|(k, _)| k.clone())
        .collect();
    if sections.len() < 2 {
        return "no second table".into();
    }
    let from = sections.choose(rng).unwrap().clone();
    let to = sections.choose(rng).unwrap().clone();
    let Some(Value::Table(f)) = doc.get_mut(&from) else {
        return "no table".into();
    };
    let keys: Vec<String> = f.keys().cloned().collect();
    let Some(k) = keys.choose(rng).cloned() else {
        return "empty table".into();
    };
    let v = f.remove(&k).unwrap();
    if let Some(Value::Table(t)) = doc.get_mut(&to) {
        t.insert(k.clone(), v);
    }
    format!("moved {from}.{k} to [{to}]")
}

/// A unicode key in a random table (or at the top).
pub fn unicode_key(rng: &mut ChaCha8Rng, doc: &mut Table) -> String {
    let key = UNICODE.choose(rng).unwrap().to_string();
    let sections: Vec<String> = doc
        .iter()
        .filter(|(_, v)| v.is_table())
        .map(|(k, _)| k.clone())
        .collect();
    match sections.choose(rng) {
        Some(s) if rng.gen_bool(0.8) => {
            if let Some(Value::Table(t)) = doc.get_mut(s) {
                t.insert(key.clone(), Value::Integer(1));
            }
            format!("unicode key {key:?} in [{s}]")
        }
        _ => {
            doc.insert(key.clone(), Value::Integer(1));
            format!("unicode key {key:?} at the top")
        }
    }
}

/// Text mutations: a key written twice, a table header written twice, an integer beyond 64
/// bits. Returns None when the text has nothing to mutate.
pub fn text_mutation(rng: &mut ChaCha8Rng, text: &mut String) -> Option<String> {
    let lines: Vec<&str> = text.lines().collect();
    let keys: Vec<usize> = (0..lines.len())
        .filter(|&i| {
            let l = lines[i].trim_start();
            !l.starts_with('[') && !l.starts_with('#') && l.contains(" = ")
        })
        .collect();
    let headers: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].starts_with('[') && !lines[i].starts_with("[["))
        .collect();
    let kind = rng.gen_range(0..3);
    let (new, what) = match kind {
        0 => {
            let &i = keys.choose(rng)?;
            let mut l: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
            l.insert(i + 1, lines[i].to_string());
            (l.join("\n"), format!("line {} written twice", i + 1))
        }
        1 => {
            let &i = headers.choose(rng)?;
            (
                format!("{text}\n{}\nx_dup = 1\n", lines[i]),
                format!("table {} written twice", lines[i]),
            )
        }
        _ => {
            let &i = keys.choose(rng)?;
            let mut l: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
            let key = lines[i].split(" = ").next().unwrap_or("x").to_string();
            l[i] = format!("{key} = 99999999999999999999");
            (
                l.join("\n"),
                format!("line {}: integer beyond 64 bits", i + 1),
            )
        }
    };
    *text = new + "\n";
    Some(what)
}
