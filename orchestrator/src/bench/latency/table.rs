//! The latency table: one row per (path, payload), the ratios between rows of the same run,
//! and its printing.

use super::{Path, SIZES};
use serde::Serialize;

/// One (path, payload) row: p50 / p99 of both variants, in microseconds.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub path: String,
    pub payload_bytes: usize,
    pub rounds: u64,
    pub poll_p50_us: f64,
    pub poll_p99_us: f64,
    pub block_p50_us: f64,
    pub block_p99_us: f64,
}

/// A ratio of two rows of the same run, at one payload size and variant.
#[derive(Debug, Clone, Serialize)]
pub struct Ratio {
    pub what: String,
    pub payload_bytes: usize,
    pub mode: String,
    pub p50_ratio: f64,
    pub p99_ratio: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct Report {
    pub rows: Vec<Row>,
    pub ratios: Vec<Ratio>,
}

/// The ratios printed under the table, each at every payload size both rows have.
pub(super) fn ratios(rows: &[Row], sense_bytes: usize) -> Vec<Ratio> {
    let find = |p: Path, s: usize| {
        rows.iter()
            .find(|r| r.path == p.label() && r.payload_bytes == s)
    };
    let mut ratios = Vec::new();
    let mut add = |what: &str, a: Path, b: Path, s: usize| {
        if let (Some(x), Some(y)) = (find(a, s), find(b, s)) {
            for (mode, (x50, x99, y50, y99)) in [
                (
                    "poll",
                    (x.poll_p50_us, x.poll_p99_us, y.poll_p50_us, y.poll_p99_us),
                ),
                (
                    "block",
                    (
                        x.block_p50_us,
                        x.block_p99_us,
                        y.block_p50_us,
                        y.block_p99_us,
                    ),
                ),
            ] {
                ratios.push(Ratio {
                    what: what.to_string(),
                    payload_bytes: s,
                    mode: mode.to_string(),
                    p50_ratio: x50 / y50,
                    p99_ratio: x99 / y99,
                });
            }
        }
    };
    for &s in &SIZES {
        add("runtime radio / raw iceoryx2", Path::Radio, Path::Iox2, s);
    }
    for &s in &SIZES {
        add(
            "runtime radio, bytes / raw iceoryx2",
            Path::RadioBytes,
            Path::Iox2,
            s,
        );
    }
    for &s in &SIZES {
        add(
            "runtime radio, blob / raw iceoryx2",
            Path::RadioBlob,
            Path::Iox2,
            s,
        );
    }
    add(
        "runtime Sense / raw iceoryx2",
        Path::Sense,
        Path::Iox2,
        sense_bytes,
    );
    for &s in &SIZES {
        add("UDS + bincode / raw iceoryx2", Path::Uds, Path::Iox2, s);
    }
    for &s in &SIZES {
        add(
            "UDS + bincode / runtime radio, bytes",
            Path::Uds,
            Path::RadioBytes,
            s,
        );
    }
    ratios
}

fn human(b: usize) -> String {
    if b >= 1 << 20 && b.is_multiple_of(1 << 20) {
        format!("{} MiB", b >> 20)
    } else if b >= 1024 && b.is_multiple_of(1024) {
        format!("{} KiB", b >> 10)
    } else {
        format!("{b} B")
    }
}

pub fn print(r: &Report) {
    println!("one-hop latency between two processes, microseconds (p50 / p99 of the rounds after a warm-up)");
    println!(
        "{:<22} {:>9} {:>7} | {:>9} {:>9} | {:>9} {:>9}",
        "path", "payload", "rounds", "poll p50", "poll p99", "block p50", "block p99"
    );
    let mut last = String::new();
    for x in &r.rows {
        if x.path != last && !last.is_empty() {
            println!("{}", "-".repeat(86));
        }
        last = x.path.clone();
        println!(
            "{:<22} {:>9} {:>7} | {:>9.1} {:>9.1} | {:>9.1} {:>9.1}",
            x.path,
            human(x.payload_bytes),
            x.rounds,
            x.poll_p50_us,
            x.poll_p99_us,
            x.block_p50_us,
            x.block_p99_us
        );
    }
    println!("ratios measured in this run (p50 ratio / p99 ratio):");
    println!(
        "{:<38} {:>9} | {:>15} | {:>15}",
        "", "payload", "poll", "block"
    );
    for pair in r.ratios.chunks(2) {
        let (p, b) = (&pair[0], &pair[1]);
        println!(
            "{:<38} {:>9} | {:>6.2}x {:>6.2}x | {:>6.2}x {:>6.2}x",
            p.what,
            human(p.payload_bytes),
            p.p50_ratio,
            p.p99_ratio,
            b.p50_ratio,
            b.p99_ratio
        );
    }
    println!("blocking wake: runtime paths through the tick barrier's futex words, raw iceoryx2 through an iceoryx2 event, UDS in read(2).");
}
