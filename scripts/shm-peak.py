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
dyn_kind = {}      # dynamic file name -> kind
dyn_bytes = {}     # dynamic file name -> content
port_kind = {}     # publisher port id -> kind


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
        if n in services.values():
            continue
        try:
            t = open(os.path.join(d, n), "rb").read().decode("latin1")
        except OSError:
            continue
        m, u = re.search(r'service_name = "(.*)"', t), re.search(r"unique_value = (\d+)", t)
        if m and u:
            services[int(u.group(1))] = kind_of_service(m.group(1))


def kind(name):
    if name == pfx + "tick":
        return "barrier"
    if name == pfx + "air" or name.startswith(pfx + "air."):
        return "air"
    rest = name[len(pfx):]
    parts = rest.split("_")
    if name.endswith(".dynamic") and len(parts) >= 2:
        if name not in dyn_kind:
            learn_services()
            k = services.get(int(parts[1].split(".")[0]) >> 64)
            if k is None:
                return "other"
            dyn_kind[name] = k
            try:
                dyn_bytes[name] = open(os.path.join(SHM, name), "rb").read()
            except OSError:
                dyn_bytes[name] = b""
        return dyn_kind[name]
    if (name.endswith(".data") and "__" not in name) or name.endswith(".connection"):
        try:
            port = int(parts[1].split(".")[0])
        except (IndexError, ValueError):
            return "other"
        if port not in port_kind:
            b = port.to_bytes(16, "little")
            for d, content in dyn_bytes.items():
                if b in content:
                    port_kind[port] = dyn_kind[d]
                    break
            else:
                return "other"
        return port_kind[port]
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
    # Dynamic configs first, so data files can find their port in them.
    for n, _, _, d in sorted(fs, key=lambda f: not f[0].endswith(".dynamic")):
        if not d:
            kind(n)
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
