//! Open-file limits (issue 14 item 5). Every robot costs the world process file descriptors
//! (its sense, act and radio services and their ports), so `--robots 4096` died with EMFILE
//! (`create sense service: InternalFailure`) under the usual soft limit of 1,024. The
//! orchestrator and the world raise the soft RLIMIT_NOFILE to the hard limit at start (the
//! world and agents inherit it), and `up` refuses a run whose world cannot fit under it.

/// World descriptors that do not depend on N (std streams, the node, status and control
/// services, the barrier, the run's output files), from `bench memory` (world fds 260 at
/// N = 20 and 1,220 at N = 100, 2026-12-01: 20 + 12 N), rounded up.
pub const WORLD_FDS_BASE: u64 = 32;
/// World descriptors per robot (its sense, act and radio services, its ports and their
/// connections), the slope of the same measurement.
pub const WORLD_FDS_PER_ROBOT: u64 = 12;
/// Agent descriptors that do not depend on its links (same measurement: 72 at 7.0 links,
/// 213 at 30.4 links per agent: ~30 + 6 per link), rounded up.
pub const AGENT_FDS_BASE: u64 = 40;
/// Agent descriptors per radio link (the subscriber's port and connection segments).
pub const AGENT_FDS_PER_LINK: u64 = 7;

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

/// Descriptors an agent with at most `links` radio links needs.
pub fn agent_fds_needed(links: u64) -> u64 {
    AGENT_FDS_BASE + AGENT_FDS_PER_LINK * links
}

/// Whether an N-robot run whose agents hold at most `links` links each fits under the soft
/// limit `soft` (already raised to the hard one): the error says why and which limit to
/// raise.
pub fn check_fits(robots: u32, links: u64, soft: u64) -> Result<(), String> {
    let world = world_fds_needed(robots);
    let agent = agent_fds_needed(links);
    let how = |need: u64| {
        format!(
            "raise the hard open-files limit (RLIMIT_NOFILE; `ulimit -Hn {need}` as root, \
             `LimitNOFILE=` in a systemd unit, `nofile` in /etc/security/limits.conf)"
        )
    };
    if world > soft {
        return Err(format!(
            "--robots {robots} needs about {world} open files in the world process \
             ({WORLD_FDS_BASE} + {WORLD_FDS_PER_ROBOT} per robot) but the limit is {soft} \
             (RLIMIT_NOFILE, already raised to its hard limit): {}, or run at most {} robots",
            how(world),
            soft.saturating_sub(WORLD_FDS_BASE) / WORLD_FDS_PER_ROBOT
        ));
    }
    if agent > soft {
        return Err(format!(
            "an agent with up to {links} radio links (radio.max_links + radio.lingering_links, \
             at most robots - 1) needs about {agent} open files ({AGENT_FDS_BASE} + \
             {AGENT_FDS_PER_LINK} per link) but the limit is {soft} (RLIMIT_NOFILE, already \
             raised to its hard limit): {}, or lower radio.max_links / radio.lingering_links",
            how(agent)
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_fits_or_says_which_limit_to_raise() {
        assert!(check_fits(50, 49, 1024).is_ok());
        assert_eq!(world_fds_needed(4096), 32 + 12 * 4096);
        let e = check_fits(4096, 256, 1024).unwrap_err();
        assert!(
            e.contains("RLIMIT_NOFILE") && e.contains("ulimit -Hn 49184"),
            "{e}"
        );
        // (1024 - 32) / 12 = 82 robots fit under 1,024.
        assert!(e.contains("at most 82 robots"), "{e}");
        assert!(check_fits(82, 81, 1024).is_ok() && check_fits(83, 82, 1024).is_err());
        // 40 + 7 x 256 = 1832 for an agent with the default 128 + 128 links.
        let e = check_fits(82, 256, 1024).unwrap_err();
        assert!(e.contains("1832") && e.contains("radio.max_links"), "{e}");
    }

    #[test]
    fn the_soft_limit_is_raised_to_the_hard_one() {
        let (soft, hard) = raise_nofile();
        assert_eq!(soft, hard);
        assert!(soft > 0);
    }
}
