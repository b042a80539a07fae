//! The rows' "hosts": network namespaces on this machine, made with `ip` (iproute2). The
//! world's namespace is joined to each host's by a veth pair (link H: 10.99.H.1 on the world's
//! side, 10.99.H.2 on the host's); nothing else is in them, so Zenoh and the round trip use
//! those links only. [`Net`] removes every namespace it made when dropped (its veths go with
//! them), on success, on error and after a Ctrl-C alike.

use super::error::HostsBenchError;
use std::fs::File;
use std::net::Ipv4Addr;
use std::os::fd::{AsRawFd, RawFd};
use std::process::Command;

/// The start of every namespace and veth name the bench makes: `swb<pid>w` (the world's),
/// `swb<pid>h<H>` (host H's), `swb<pid>a<H>` / `swb<pid>b<H>` (link H's ends), the bench's pid
/// in it so that benches in parallel do not meet and a killed bench's are known as stale.
const NAME_START: &str = "swb";

/// The second byte of every link's addresses (10.LINK_NET.H.0/24). [chosen] Each link lies
/// between namespaces of its own, so it cannot clash with any network of the machine.
const LINK_NET: u8 = 99;

/// Where `ip netns` keeps a handle of each named namespace.
const NETNS_DIR: &str = "/run/netns";

/// Why the rows cannot run here, if they cannot: not root, or no `ip`.
pub fn unavailable() -> Option<String> {
    // SAFETY: geteuid cannot fail.
    if unsafe { libc::geteuid() } != 0 {
        return Some("they need root (network namespaces, `ip netns`)".into());
    }
    match Command::new("ip").arg("-V").output() {
        Ok(o) if o.status.success() => None,
        Ok(o) => Some(format!(
            "`ip -V` failed: {}",
            String::from_utf8_lossy(&o.stderr).trim()
        )),
        Err(e) => Some(format!("no `ip` command (iproute2): {e}")),
    }
}

/// Runs `program args`: Err with its stderr when it fails.
fn run(program: &str, args: &[&str]) -> Result<(), HostsBenchError> {
    let command = format!("{program} {}", args.join(" "));
    let o = Command::new(program)
        .args(args)
        .output()
        .map_err(|e| HostsBenchError::Command {
            command: command.clone(),
            message: e.to_string(),
        })?;
    if o.status.success() {
        Ok(())
    } else {
        Err(HostsBenchError::Command {
            command,
            message: String::from_utf8_lossy(&o.stderr).trim().to_string(),
        })
    }
}

/// Removes the namespaces of benches that are no longer running (killed before their guard
/// could): names `swb<pid>...` whose pid is gone.
pub fn remove_stale() {
    let Ok(dir) = std::fs::read_dir(NETNS_DIR) else {
        return;
    };
    for name in dir
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
    {
        let Some(rest) = name.strip_prefix(NAME_START) else {
            continue;
        };
        let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
        let Ok(pid) = digits.parse::<u32>() else {
            continue;
        };
        if pid != std::process::id() && !std::path::Path::new(&format!("/proc/{pid}")).exists() {
            let _ = run("ip", &["netns", "del", &name]);
        }
    }
}

/// The world's namespace and the hosts' namespaces, joined by veth pairs.
pub struct Net {
    world: String,
    hosts: Vec<String>,
    /// Namespaces made so far (removed on drop).
    made: Vec<String>,
    /// Whether a netem qdisc may be on the links.
    delayed: bool,
}

impl Net {
    /// The world's namespace and `hosts` hosts' namespaces.
    pub fn new(hosts: usize) -> Result<Net, HostsBenchError> {
        let pid = std::process::id();
        let mut net = Net {
            world: format!("{NAME_START}{pid}w"),
            hosts: (1..=hosts)
                .map(|h| format!("{NAME_START}{pid}h{h}"))
                .collect(),
            made: Vec::new(),
            delayed: false,
        };
        let world = net.world.clone();
        net.add(&world)?;
        for h in 1..=hosts {
            let ns = net.hosts[h - 1].clone();
            net.add(&ns)?;
            let (a, b) = (
                format!("{NAME_START}{pid}a{h}"),
                format!("{NAME_START}{pid}b{h}"),
            );
            run(
                "ip",
                &[
                    "link", "add", &a, "netns", &world, "type", "veth", "peer", "name", &b,
                    "netns", &ns,
                ],
            )?;
            let (wa, ha) = (
                format!("{}/24", Net::world_addr(h)),
                format!("{}/24", Net::host_addr(h)),
            );
            run("ip", &["-n", &world, "addr", "add", &wa, "dev", &a])?;
            run("ip", &["-n", &ns, "addr", "add", &ha, "dev", &b])?;
            run("ip", &["-n", &world, "link", "set", &a, "up"])?;
            run("ip", &["-n", &ns, "link", "set", &b, "up"])?;
        }
        Ok(net)
    }

    fn add(&mut self, ns: &str) -> Result<(), HostsBenchError> {
        run("ip", &["netns", "add", ns])?;
        self.made.push(ns.to_string());
        run("ip", &["-n", ns, "link", "set", "lo", "up"])
    }

    pub fn world(&self) -> &str {
        &self.world
    }

    /// Host `h`'s namespace (1-based).
    pub fn host(&self, h: usize) -> &str {
        &self.hosts[h - 1]
    }

    pub fn hosts(&self) -> usize {
        self.hosts.len()
    }

    /// The world's address on link `h`.
    pub fn world_addr(h: usize) -> Ipv4Addr {
        Ipv4Addr::new(10, LINK_NET, h as u8, 1)
    }

    /// Host `h`'s address on its link.
    pub fn host_addr(h: usize) -> Ipv4Addr {
        Ipv4Addr::new(10, LINK_NET, h as u8, 2)
    }

    /// Both ends of link `h`: (namespace, device).
    fn ends(&self, h: usize) -> [(String, String); 2] {
        let pid = std::process::id();
        [
            (self.world.clone(), format!("{NAME_START}{pid}a{h}")),
            (self.host(h).to_string(), format!("{NAME_START}{pid}b{h}")),
        ]
    }

    /// A `tc netem` delay of `ms` on every link, each way (0: none). Err: tc's own words when
    /// it refuses (a kernel without sch_netem); the links are then left without delay.
    pub fn set_delay(&mut self, ms: f64) -> Result<(), String> {
        if self.delayed {
            for h in 1..=self.hosts() {
                for (ns, dev) in self.ends(h) {
                    let _ = run("tc", &["-n", &ns, "qdisc", "del", "dev", &dev, "root"]);
                }
            }
            self.delayed = false;
        }
        if ms <= 0.0 {
            return Ok(());
        }
        let delay = format!("{ms}ms");
        for h in 1..=self.hosts() {
            for (ns, dev) in self.ends(h) {
                let r = run(
                    "tc",
                    &[
                        "-n", &ns, "qdisc", "add", "dev", &dev, "root", "netem", "delay", &delay,
                    ],
                );
                if let Err(e) = r {
                    let why = match e {
                        HostsBenchError::Command { message, .. } => message,
                        other => other.to_string(),
                    };
                    let _ = self.set_delay(0.0);
                    return Err(why);
                }
                self.delayed = true;
            }
        }
        Ok(())
    }
}

impl Drop for Net {
    fn drop(&mut self) {
        for ns in self.made.iter().rev() {
            let _ = run("ip", &["netns", "del", ns]);
        }
    }
}

/// A handle of a named network namespace, to enter it from a thread or a child process.
pub struct Netns {
    name: String,
    file: File,
}

impl Netns {
    pub fn open(name: &str) -> Result<Netns, HostsBenchError> {
        let path = std::path::Path::new(NETNS_DIR).join(name);
        File::open(&path)
            .map(|file| Netns {
                name: name.to_string(),
                file,
            })
            .map_err(|source| HostsBenchError::Netns {
                name: name.to_string(),
                source,
            })
    }

    /// The handle's descriptor (close-on-exec), for a child's `pre_exec`: [`enter_fd`].
    pub fn fd(&self) -> RawFd {
        self.file.as_raw_fd()
    }

    /// Moves the calling thread (only it: a network namespace is per thread) into this one.
    pub fn enter(&self) -> Result<(), HostsBenchError> {
        enter_fd(self.fd()).map_err(|source| HostsBenchError::Netns {
            name: self.name.clone(),
            source,
        })
    }
}

/// setns(fd, CLONE_NEWNET) of the calling thread. Async-signal-safe (one system call), so a
/// child's `pre_exec` may call it.
pub fn enter_fd(fd: RawFd) -> std::io::Result<()> {
    // SAFETY: setns with a descriptor of an open namespace handle; it changes only the
    // calling thread's network namespace.
    if unsafe { libc::setns(fd, libc::CLONE_NEWNET) } == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}
