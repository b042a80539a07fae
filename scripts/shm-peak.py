#!/usr/bin/env python3
"""Samples one run's /dev/shm use while PID lives (scripts/shm-peak.sh): every 0.25 s the
resident size (du: allocated blocks) and the apparent size (file lengths) of /dev/shm/PFX*,
and at the resident peak a breakdown by service kind (air, sense, act, control, barrier,
other). iceoryx2 files are attributed to their service: a publisher's data segment
(<pfx><hash>_<port>.data) and its connections (..._<port>_<sub>.connection) through the
dynamic config that lists the port, a dynamic config (<pfx><hash>_<id>.dynamic) through
id >> 64 = its service's unique_value (in <pfx>iox2/services/*.service)."""
import os, re, sys, time

pid, pfx = int(sys.argv[1]), sys.argv[2]
SHM = "/dev/shm"
services = {}      # unique_value -> kind
seen_services = set()
dyn_bytes = {}     # dynamic config files read
port_dyn = {}      # 16-byte window of a dynamic config (a port id) -> that file


def kind_of_service(name):
    if name.endswith("/sense"):
        return "sense"
    if name.endswith("/act"):
        return "act"
    if name == "radio/air":
        return "air"
    if name in ("run/control", "world/state"):
        return "control"
    return "other"


def learn_services():
    d = os.path.join(SHM, pfx + "iox2", "services")
    try:
        names = os.listdir(d)
    except OSError:
        return
    for n in names:
        if n in seen_services:
            continue
        seen_services.add(n)
        try:
            t = open(os.path.join(d, n), "rb").read().decode("latin1")
        except OSError:
            continue
        m, u = re.search(r'service_name = "(.*)"', t), re.search(r"unique_value = (\d+)", t)
        if m and u:
            services[int(u.group(1))] = kind_of_service(m.group(1))


def learn_dynamic(name):
    """Reads a dynamic config once, indexing every 8-aligned 16-byte window (port ids)."""
    if name in dyn_bytes:
        return
    try:
        content = open(os.path.join(SHM, name), "rb").read()
    except OSError:
        return
    dyn_bytes[name] = True
    for at in range(0, len(content) - 15, 8):
        port_dyn.setdefault(content[at:at + 16], name)


def dyn_service_kind(name):
    parts = name[len(pfx):].split("_")
    try:
        return services.get(int(parts[1].split(".")[0]) >> 64, "other")
    except (IndexError, ValueError):
        return "other"


def kind(name):
    """The kind of one file of the run, from what was learned while it ran."""
    if name == pfx + "tick":
        return "barrier"
    if name == pfx + "air" or name.startswith(pfx + "air."):
        return "air"
    if name == pfx + "sense" or name.startswith(pfx + "sense."):
        return "sense"  # the Sense frames' ring (runtime.sense = "ring")
    parts = name[len(pfx):].split("_")
    if name.endswith(".dynamic"):
        return dyn_service_kind(name)
    if (name.endswith(".data") and "__" not in name) or name.endswith(".connection"):
        try:
            port = int(parts[1].split(".")[0])
        except (IndexError, ValueError):
            return "other"
        d = port_dyn.get(port.to_bytes(16, "little"))
        return dyn_service_kind(d) if d else "other"
    return "other"


def scan():
    files = []
    for e in os.scandir(SHM):
        if not e.name.startswith(pfx):
            continue
        try:
            if e.is_dir(follow_symlinks=False):
                tot_a = tot_b = 0
                for root, _, fs in os.walk(e.path):
                    for f in fs:
                        try:
                            st = os.lstat(os.path.join(root, f))
                        except OSError:
                            continue
                        tot_a += st.st_size
                        tot_b += st.st_blocks * 512
                files.append((e.name, tot_a, tot_b, True))
            else:
                st = e.stat(follow_symlinks=False)
                files.append((e.name, st.st_size, st.st_blocks * 512, False))
        except OSError:
            continue
    return files


def alive(p):
    try:
        os.kill(p, 0)
        return True
    except OSError:
        return False


peak_du, peak_app, at_peak = 0, 0, []
while alive(pid):
    fs = scan()
    # Learn the new services and dynamic configs (each file is read once).
    learn_services()
    for n, _, _, d in fs:
        if not d and n.endswith(".dynamic"):
            learn_dynamic(n)
    du = sum(f[2] for f in fs)
    app = sum(f[1] for f in fs)
    peak_app = max(peak_app, app)
    if du > peak_du:
        peak_du, at_peak = du, fs
    time.sleep(0.25)
print(f"shm_max_kib={peak_du // 1024} apparent_max_kib={peak_app // 1024}")
by = {}
for n, a, b, d in at_peak:
    k = "other" if d else kind(n)
    s = by.setdefault(k, [0, 0, 0])
    s[0] += b
    s[1] += a
    s[2] += 1
print("at the resident peak, by kind: du KiB / apparent KiB / files")
for k in ["air", "sense", "act", "control", "barrier", "other"]:
    if k in by:
        b, a, c = by[k]
        print(f"  {k:8} {b // 1024:>9} {a // 1024:>9} {c:>6}")
