//! Run ids: UTC time plus a random suffix, e.g. `20261122-183500-3fa2`.

use std::time::{SystemTime, UNIX_EPOCH};

/// Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
fn civil(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + (m <= 2) as i64;
    (y, m, d)
}

/// The environment variable that fixes the next run's id (tests and scripts that must know a
/// run's shared-memory prefix before it starts; it must be a valid id, see [`is_valid`]:
/// `orchestrator up` refuses another, the sweeps and benchmarks ignore it).
pub const RUN_ID_ENV: &str = "SWARM_RUN_ID";
/// The longest run id.
pub const MAX_LEN: usize = 40;

/// Whether `id` has the form of a run id: 1 to MAX_LEN letters, digits and dashes, not
/// starting with a dash (it names files: no `/`, no `.`).
pub fn is_valid(id: &str) -> bool {
    !id.is_empty()
        && id.len() <= MAX_LEN
        && !id.starts_with('-')
        && id.chars().all(|c| c.is_ascii_alphanumeric() || c == '-')
}

/// `SWARM_RUN_ID`, if set: Err names it and the allowed form when it is not a run id.
pub fn from_env() -> Result<Option<String>, String> {
    match std::env::var(RUN_ID_ENV) {
        Ok(id) if is_valid(&id) => Ok(Some(id)),
        Ok(id) => Err(format!(
            "{RUN_ID_ENV}={id:?} is not a run id: allowed are 1 to {MAX_LEN} ASCII letters, \
             digits and dashes, not starting with a dash"
        )),
        Err(_) => Ok(None),
    }
}

pub fn new_run_id() -> String {
    if let Ok(Some(id)) = from_env() {
        return id;
    }
    let now = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .expect("clock after 1970");
    let secs = now.as_secs() as i64;
    let (y, mo, d) = civil(secs.div_euclid(86_400));
    let s = secs.rem_euclid(86_400);
    // Not a simulation draw: only makes concurrent runs' ids differ.
    let salt = (now.subsec_nanos() ^ std::process::id().wrapping_mul(2_654_435_761)) & 0xffff;
    format!(
        "{y:04}{mo:02}{d:02}-{:02}{:02}{:02}-{salt:04x}",
        s / 3600,
        s / 60 % 60,
        s % 60
    )
}

#[cfg(test)]
mod tests {
    #[test]
    fn run_id_forms() {
        assert!(super::is_valid(&super::new_run_id()));
        assert!(super::is_valid("e2e-123-x"));
        for bad in ["", "../x", "a/b", "a.json", "-x", &"x".repeat(41)] {
            assert!(!super::is_valid(bad), "{bad:?}");
        }
    }

    #[test]
    fn civil_dates() {
        assert_eq!(super::civil(0), (1970, 1, 1));
        assert_eq!(super::civil(20_414), (2025, 11, 22));
    }
}
