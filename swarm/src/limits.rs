//! Open-file limits (issue 14 item 5). Every robot costs the world process file descriptors
//! (its sense and act services and their ports), so `--robots 4096` died with EMFILE
//! (`create sense service: InternalFailure`) under the usual soft limit of 1,024. The
//! orchestrator and the world raise the soft RLIMIT_NOFILE to the hard limit at start (the
//! world and agents inherit it), and `up` refuses a run whose world cannot fit under it.

/// World descriptors that do not depend on N (std streams, the node, status and control
/// services, the barrier, the run's output files), from `bench memory` (world fds 260 at
/// N = 20 and 1,220 at N = 100, 2026-12-01: 20 + 12 N), rounded up.
pub const WORLD_FDS_BASE: u64 = 32;
/// World descriptors per robot (its sense and act services, its ports and their connections;
/// measured when each robot also had a radio service, so an upper bound now).
pub const WORLD_FDS_PER_ROBOT: u64 = 12;
/// The soft and hard RLIMIT_NOFILE after raising the soft limit to the hard one.
pub fn raise_nofile() -> (u64, u64) {
    let mut r = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit / setrlimit with a valid pointer.
    unsafe {
        if libc::getrlimit(libc::RLIMIT_NOFILE, &mut r) != 0 {
            return (0, 0);
        }
        if r.rlim_cur < r.rlim_max {
            let want = libc::rlimit {
                rlim_cur: r.rlim_max,
                rlim_max: r.rlim_max,
            };
            if libc::setrlimit(libc::RLIMIT_NOFILE, &want) == 0 {
                r.rlim_cur = r.rlim_max;
            }
        }
    }
    (r.rlim_cur, r.rlim_max)
}

/// Descriptors the world of an N-robot run needs.
pub fn world_fds_needed(robots: u32) -> u64 {
    WORLD_FDS_BASE + WORLD_FDS_PER_ROBOT * robots as u64
}

/// Whether an N-robot run fits under the soft limit `soft` (already raised to the hard one):
/// the error says why and which limit to raise. (An agent's descriptors no longer grow with
/// the swarm: it opens its sense and act services and the one air service.)
pub fn check_fits(robots: u32, soft: u64) -> Result<(), String> {
    let world = world_fds_needed(robots);
    if world > soft {
        return Err(format!(
            "--robots {robots} needs about {world} open files in the world process \
             ({WORLD_FDS_BASE} + {WORLD_FDS_PER_ROBOT} per robot) but the limit is {soft} \
             (RLIMIT_NOFILE, already raised to its hard limit): raise the hard open-files \
             limit (RLIMIT_NOFILE; `ulimit -Hn {world}` as root, `LimitNOFILE=` in a systemd \
             unit, `nofile` in /etc/security/limits.conf), or run at most {} robots",
            soft.saturating_sub(WORLD_FDS_BASE) / WORLD_FDS_PER_ROBOT
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_fits_or_says_which_limit_to_raise() {
        assert!(check_fits(50, 1024).is_ok());
        assert_eq!(world_fds_needed(4096), 32 + 12 * 4096);
        let e = check_fits(4096, 1024).unwrap_err();
        assert!(
            e.contains("RLIMIT_NOFILE") && e.contains("ulimit -Hn 49184"),
            "{e}"
        );
        // (1024 - 32) / 12 = 82 robots fit under 1,024.
        assert!(e.contains("at most 82 robots"), "{e}");
        assert!(check_fits(82, 1024).is_ok() && check_fits(83, 1024).is_err());
    }

    #[test]
    fn the_soft_limit_is_raised_to_the_hard_one() {
        let (soft, hard) = raise_nofile();
        assert_eq!(soft, hard);
        assert!(soft > 0);
    }
}
