//! Runs across hosts (issue 41) between network namespaces on this machine: the world's host
//! in one namespace, each remote host's proxy (`orchestrator host`) in its own, joined by veth
//! pairs with addresses of private /24s. Zenoh speaks over those addresses only (no scouting,
//! no other interface exists in the namespaces). Real processes, real SIGKILLs. Needs root
//! (`ip netns`): skipped with a message otherwise. Every namespace is removed afterwards.

use e2e::*;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The port the world's host listens on (in its own namespace: nothing else is there).
const PORT: u16 = 7447;

/// A world namespace and `hosts` host namespaces, each joined to the world's by a veth pair
/// (world side 10.X.H.1, host side 10.X.H.2, X from this test process's pid).
struct Net {
    world: String,
    hosts: Vec<String>,
    net: u32,
}

fn ip(args: &[&str]) {
    let o = Command::new("ip")
        .args(args)
        .output()
        .expect("ip (iproute2) must be installed: scripts/test.sh installs it");
    assert!(
        o.status.success(),
        "ip {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&o.stderr)
    );
}

impl Net {
    fn new(hosts: usize) -> Net {
        let pid = std::process::id();
        let net = 20 + pid % 200;
        let world = format!("swt{pid}w");
        let names: Vec<String> = (1..=hosts).map(|h| format!("swt{pid}h{h}")).collect();
        let n = Net {
            world: world.clone(),
            hosts: names.clone(),
            net,
        };
        ip(&["netns", "add", &world]);
        ip(&["-n", &world, "link", "set", "lo", "up"]);
        for (h, ns) in names.iter().enumerate() {
            let h = h + 1;
            let (a, b) = (format!("swv{pid}a{h}"), format!("swv{pid}b{h}"));
            ip(&["netns", "add", ns]);
            ip(&["-n", ns, "link", "set", "lo", "up"]);
            ip(&[
                "link", "add", &a, "netns", &world, "type", "veth", "peer", "name", &b, "netns", ns,
            ]);
            ip(&[
                "-n",
                &world,
                "addr",
                "add",
                &format!("10.{net}.{h}.1/24"),
                "dev",
                &a,
            ]);
            ip(&[
                "-n",
                ns,
                "addr",
                "add",
                &format!("10.{net}.{h}.2/24"),
                "dev",
                &b,
            ]);
            ip(&["-n", &world, "link", "set", &a, "up"]);
            ip(&["-n", ns, "link", "set", &b, "up"]);
        }
        n
    }

    /// The world host's endpoint as host `h` (1-based) reaches it.
    fn endpoint(&self, h: usize) -> String {
        format!("tcp/10.{}.{h}.1:{PORT}", self.net)
    }

    /// `orchestrator host` for host `h` (1-based) in its namespace, named `h<h>`.
    fn proxy(&self, h: usize) -> Child {
        Command::new("ip")
            .args(["netns", "exec", &self.hosts[h - 1]])
            .arg(orchestrator())
            .args([
                "host",
                "--join",
                &self.endpoint(h),
                "--name",
                &format!("h{h}"),
            ])
            .args(["--wait", "120"])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn the proxy")
    }

    /// `orchestrator up` in the world's namespace.
    fn up(&self, scenario: &Path, out: &Path, run_id: &str, extra: &[&str]) -> Child {
        Command::new("ip")
            .args(["netns", "exec", &self.world])
            .arg(orchestrator())
            .args(["up", "--quiet", "--out"])
            .arg(out)
            .arg("--scenario")
            .arg(scenario)
            .args(extra)
            .env("SWARM_RUN_ID", run_id)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn up")
    }
}

impl Drop for Net {
    fn drop(&mut self) {
        for ns in self.hosts.iter().chain(std::iter::once(&self.world)) {
            let _ = Command::new("ip").args(["netns", "del", ns]).output();
        }
    }
}

/// Root only (network namespaces); false, with the reason printed, otherwise.
fn can_run() -> bool {
    // SAFETY: geteuid cannot fail.
    if unsafe { libc::geteuid() } != 0 {
        eprintln!(
            "skipped: runs across hosts are tested between network namespaces, which needs root"
        );
        return false;
    }
    true
}

/// A run of `robots` robots of `behaviour` (search ends when every target is found, roam
/// lasts max_ticks); `extra` goes in `[runtime]` and after; `hosts` places ranges of robots
/// on hosts h1, h2, ...
fn scenario(name: &str, behaviour: &str, robots: u32, extra: &str, hosts: &[&str]) -> PathBuf {
    let mut s = String::new();
    if !hosts.is_empty() {
        s += &format!("hosts_listen = \"tcp/0.0.0.0:{PORT}\"\n");
    }
    s += &format!(
        "[run]\nbehaviour = \"{behaviour}\"\nrobots = {robots}\nmax_ticks = 300\nseed = 11\n[runtime]\nstartup_timeout_s = 20\n{extra}\n"
    );
    for (h, range) in hosts.iter().enumerate() {
        s += &format!("[[hosts]]\nname = \"h{}\"\nrobots = \"{range}\"\n", h + 1);
    }
    let p = std::env::temp_dir().join(format!("swarm-e2e-{}-{name}.toml", std::process::id()));
    std::fs::write(&p, s).unwrap();
    p
}

/// The proxy's prefix in /dev/shm (its own: `prefix_for(run_id@host)`).
fn proxy_prefix(run_id: &str, host: &str) -> String {
    swarm::transport::prefix_for(&format!("{run_id}@{host}"))
}

fn wait_out(c: Child, within: Duration) -> Output {
    let pid = c.id() as i32;
    let t = Instant::now();
    while pid_alive(pid) && t.elapsed() < within {
        std::thread::sleep(Duration::from_millis(20));
    }
    if pid_alive(pid) {
        // SAFETY: a child of this test.
        unsafe { libc::kill(pid, libc::SIGINT) };
    }
    c.wait_with_output().unwrap()
}

/// Nothing of the run is left: no process and no file of its world or of its proxies. Then
/// removes the proxies' run folders (kept after a run for its robots' logs).
fn assert_nothing_left(run_id: &str, hosts: &[&str]) {
    let t = Instant::now();
    let prefixes: Vec<String> = std::iter::once(swarm::transport::prefix_for(run_id))
        .chain(hosts.iter().map(|h| proxy_prefix(run_id, h)))
        .collect();
    loop {
        let files: Vec<String> = run_shm_entries()
            .into_iter()
            .filter(|f| prefixes.iter().any(|p| f.starts_with(p)))
            .collect();
        let procs: Vec<u32> = prefixes
            .iter()
            .flat_map(|p| processes_mentioning(p))
            .collect();
        if files.is_empty() && procs.is_empty() {
            for h in hosts {
                let dir = std::env::temp_dir().join(format!("swarm-host-{h}-{run_id}"));
                let _ = std::fs::remove_dir_all(dir);
            }
            return;
        }
        assert!(
            t.elapsed() < Duration::from_secs(10),
            "left: files {files:?}, processes {procs:?}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn thirty_robots_over_three_hosts_record_what_one_host_records() {
    let _g = serial();
    if !can_run() {
        return;
    }
    let net = Net::new(2);
    let across = scenario("across", "search", 30, "", &["10..20", "20..30"]);
    let one = scenario("one", "search", 30, "", &[]);
    let (a, b) = (tmp_dir("hosts-across"), tmp_dir("hosts-one"));
    let id = own_run_id("across");
    let proxies = [net.proxy(1), net.proxy(2)];
    let o = wait_out(net.up(&across, &a, &id, &[]), Duration::from_secs(240));
    assert!(ended_by_itself(&o), "across hosts: {}", stderr(&o));
    for p in proxies {
        let o = wait_out(p, Duration::from_secs(20));
        assert!(o.status.success(), "proxy: {}", stderr(&o));
    }
    let o = up(&["--scenario", one.to_str().unwrap()], &b);
    assert!(ended_by_itself(&o), "one host: {}", stderr(&o));
    let s = summary(&a);
    assert_eq!(s["robots"], 30);
    assert!(s["ticks"].as_u64().unwrap() > 20, "{s}");
    assert!(s["messages"]["delivered"].as_u64().unwrap() > 0, "{s}");
    assert!(
        same_recording(&a, &b),
        "the run across hosts records other bytes"
    );
    assert_nothing_left(&id, &["h1", "h2"]);
    assert_left_nothing(&b);
}

#[test]
fn remote_agents_killed_under_restart_come_back() {
    let _g = serial();
    if !can_run() {
        return;
    }
    let net = Net::new(1);
    let sc = scenario(
        "restart",
        "roam",
        8,
        "tick_hz = 40.0\n[faults]\non_fault = \"restart\"\nmax_restarts = 2",
        &["4..8"],
    );
    let out = tmp_dir("hosts-restart");
    let id = own_run_id("restart");
    let proxy = net.proxy(1);
    let run = net.up(&sc, &out, &id, &[]);
    let t = Instant::now();
    while registry_tick(&out) < 40 {
        assert!(
            t.elapsed() < Duration::from_secs(60),
            "the run never reached tick 40"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    // Robot 6's agent, a child of host h1's proxy.
    let needle = format!("--robot\u{0}6\u{0}--prefix\u{0}{}", proxy_prefix(&id, "h1"));
    let pids = processes_mentioning(&needle);
    assert_eq!(pids.len(), 1, "robot 6's agent on h1: {pids:?}");
    // SAFETY: SIGKILL of the agent found above.
    unsafe { libc::kill(pids[0] as i32, libc::SIGKILL) };
    // Robot 5 through `orchestrator kill`, as a user (or the viewer's button) would.
    while registry_tick(&out) < 120 {
        assert!(
            t.elapsed() < Duration::from_secs(90),
            "the run never reached tick 120"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let o = Command::new(orchestrator())
        .args(["kill", "--run", &id, "--robot", "5"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{:?} {}", o.status, stderr(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("killed robot 5 of run"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    let o = wait_out(run, Duration::from_secs(120));
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    assert!(wait_out(proxy, Duration::from_secs(20)).status.success());
    let s = summary(&out);
    assert_every_kill_restarted(&s, 2);
    assert_eq!(s["faults"][0]["robot"], 6, "{s}");
    assert_eq!(s["faults"][1]["robot"], 5, "{s}");
    assert_eq!(s["alive_at_end"], 8, "{s}");
    assert_nothing_left(&id, &["h1"]);
}

/// An `[[agents]]` entry placed on robot `robot`: `script` run by /bin/sh with the agent's
/// arguments (`$1 $2` = `--robot <i>`, ...).
fn shell_agent(robot: u32, script: &str, extra: &str) -> String {
    format!(
        "[[agents]]\nrobots = [{robot}]\ncommand = [\"/bin/sh\", \"-c\", {script:?}, \"sh\"]\n{extra}\n"
    )
}

/// `sc` with `more` (TOML) appended, written to `name`.toml in the temporary folder (the
/// recording holds an `[[agents]]` entry's source file: runs compared byte for byte read
/// their scenario from the same path).
fn with(sc: &Path, more: &str, name: &str) -> PathBuf {
    let text = std::fs::read_to_string(sc).unwrap() + more;
    let p = std::env::temp_dir().join(format!("swarm-e2e-{}-{name}.toml", std::process::id()));
    std::fs::write(&p, text).unwrap();
    p
}

/// A robot's log in a proxy's run folder (`orchestrator host`'s default --out).
fn remote_log(run_id: &str, host: &str, robot: u32) -> PathBuf {
    std::env::temp_dir()
        .join(format!("swarm-host-{host}-{run_id}"))
        .join(format!("logs/robot-{robot}.log"))
}

/// `[[agents]]` programs on a remote host run as on the world's host: the proxy starts them
/// with the sealed barrier's descriptors (without them an agent cannot attach), their output
/// goes to the robot's log in the proxy's run folder, and the run records what the same
/// scenario on one host records. One that never attaches is killed after its attach timeout
/// and fails the run fast, naming the robot, its command and its output.
#[test]
fn agents_programs_on_a_remote_host_run_log_and_time_out_there() {
    let _g = serial();
    if !can_run() {
        return;
    }
    let net = Net::new(1);
    let agent = bin_dir().join("agent");
    let wrapper = shell_agent(
        5,
        &format!(
            "echo hello from robot $2 on its host; exec {} \"$@\"",
            agent.display()
        ),
        "",
    );
    let across = with(
        &scenario("agents", "roam", 8, "", &["4..8"]),
        &wrapper,
        "wrapped",
    );
    let (a, b) = (tmp_dir("hosts-agents"), tmp_dir("hosts-agents1"));
    let id = own_run_id("agents");
    let proxy = net.proxy(1);
    let o = wait_out(net.up(&across, &a, &id, &[]), Duration::from_secs(120));
    assert!(ended_by_itself(&o), "across hosts: {}", stderr(&o));
    assert!(wait_out(proxy, Duration::from_secs(20)).status.success());
    let s = summary(&a);
    assert_eq!(s["alive_at_end"], 8, "{s}");
    let log = std::fs::read_to_string(remote_log(&id, "h1", 5)).unwrap();
    assert!(log.contains("--- swarm: agent start 1 of robot 5"), "{log}");
    assert!(log.contains("hello from robot 5 on its host"), "{log}");
    let one = with(
        &scenario("agents1", "roam", 8, "", &[]),
        &wrapper,
        "wrapped",
    );
    let o = up(&["--scenario", one.to_str().unwrap()], &b);
    assert!(ended_by_itself(&o), "one host: {}", stderr(&o));
    assert!(
        same_recording(&a, &b),
        "the run across hosts records other bytes"
    );
    assert_nothing_left(&id, &["h1"]);
    assert_left_nothing(&b);

    let hangs = shell_agent(
        6,
        "echo waiting for a licence server; exec sleep 600.321",
        "attach_timeout_s = 1",
    );
    let sc = with(
        &scenario("hangs", "roam", 8, "", &["4..8"]),
        &hangs,
        "hangs",
    );
    let out = tmp_dir("hosts-hangs");
    let id2 = own_run_id("hangs");
    let proxy = net.proxy(1);
    let t = Instant::now();
    let o = wait_out(net.up(&sc, &out, &id2, &[]), Duration::from_secs(120));
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(exit::FAILED), "{err}");
    assert!(err.contains("robot 6 failed"), "{err}");
    assert!(
        err.contains("did not attach within its attach timeout"),
        "{err}"
    );
    assert!(err.contains("waiting for a licence server"), "{err}");
    assert!(
        t.elapsed() < Duration::from_secs(30),
        "took {:?}",
        t.elapsed()
    );
    let _ = wait_out(proxy, Duration::from_secs(20));
    assert!(
        processes_mentioning("600.321").is_empty(),
        "the program lives on"
    );
    assert_nothing_left(&id2, &["h1"]);
}

#[test]
fn a_killed_proxy_makes_its_robots_faults_and_the_run_goes_on() {
    let _g = serial();
    if !can_run() {
        return;
    }
    let net = Net::new(2);
    let sc = scenario("proxykill", "roam", 9, "tick_hz = 40.0", &["3..6", "6..9"]);
    let out = tmp_dir("hosts-proxykill");
    let id = own_run_id("proxykill");
    let (p1, mut p2) = (net.proxy(1), net.proxy(2));
    let run = net.up(&sc, &out, &id, &[]);
    let t = Instant::now();
    while registry_tick(&out) < 40 {
        assert!(
            t.elapsed() < Duration::from_secs(60),
            "the run never reached tick 40"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    p2.kill().unwrap();
    p2.wait().unwrap();
    let o = wait_out(run, Duration::from_secs(120));
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("host h2 left the run"),
        "{}",
        stderr(&o)
    );
    assert!(wait_out(p1, Duration::from_secs(20)).status.success());
    let s = summary(&out);
    assert_eq!(s["ticks"], 300, "the run went on to its end: {s}");
    let dead: Vec<u64> = s["faults"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["robot"].as_u64().unwrap())
        .collect();
    assert_eq!(dead, vec![6, 7, 8], "{s}");
    assert_eq!(s["alive_at_end"], 6, "{s}");
    // The SIGKILLed proxy could not remove its files: `orchestrator clean` (run by every
    // `up`, too) removes them once nothing holds them and none changed for 10 s (its
    // ORPHAN_GRACE).
    let t = Instant::now();
    while !processes_mentioning(&proxy_prefix(&id, "h2")).is_empty() {
        assert!(
            t.elapsed() < Duration::from_secs(10),
            "h2's agents outlived their proxy"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    assert!(!run_shm_entries()
        .iter()
        .all(|f| !f.starts_with(&proxy_prefix(&id, "h2"))));
    std::thread::sleep(Duration::from_secs(11));
    let o = Command::new(orchestrator()).arg("clean").output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert_nothing_left(&id, &["h1", "h2"]);
}

#[test]
fn a_host_that_never_joins_is_named_within_the_timeout() {
    let _g = serial();
    if !can_run() {
        return;
    }
    let net = Net::new(2);
    let sc = scenario(
        "nojoin",
        "roam",
        6,
        "startup_timeout_s = 3",
        &["2..4", "4..6"],
    );
    // startup_timeout_s appears twice otherwise: the scenario's own line replaces it.
    let text = std::fs::read_to_string(&sc)
        .unwrap()
        .replace("startup_timeout_s = 20\n", "");
    std::fs::write(&sc, text).unwrap();
    let out = tmp_dir("hosts-nojoin");
    let id = own_run_id("nojoin");
    let p1 = net.proxy(1);
    let t = Instant::now();
    let o = wait_out(net.up(&sc, &out, &id, &[]), Duration::from_secs(30));
    assert_eq!(o.status.code(), Some(exit::FAILED), "{}", stderr(&o));
    assert!(
        t.elapsed() < Duration::from_secs(15),
        "took {:?}",
        t.elapsed()
    );
    let e = stderr(&o);
    assert!(e.contains("host(s) h2 did not join"), "{e}");
    assert!(e.contains("startup_timeout_s = 3 s"), "{e}");
    // The proxy that came is still waiting for a run: it is stopped here.
    // SAFETY: SIGINT to the proxy this test started.
    unsafe { libc::kill(p1.id() as i32, libc::SIGINT) };
    let o = wait_out(p1, Duration::from_secs(10));
    assert!(o.status.success(), "{}", stderr(&o));
    assert_nothing_left(&id, &["h1", "h2"]);
}
