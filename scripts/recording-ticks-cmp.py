#!/usr/bin/env python3
"""Compares the tick records of two recording.bin files, header skipped (bincode 2 standard
varints: version, robots, seed, then the scenario string). Usage: A_DIR B_DIR RUN_NAME...
(each RUN_NAME/recording.bin under both folders)."""
import sys
def varint(b, i):
    x=b[i]
    if x<251: return x, i+1
    n={251:2,252:4,253:8}[x]
    return int.from_bytes(b[i+1:i+1+n],'little'), i+1+n
def body(path):
    b=open(path,'rb').read()
    i=0
    for _ in range(3):
        _, i = varint(b, i)
    n, i = varint(b, i)
    return b[:i+n], b[i+n:]
ok=True
for name in sys.argv[3:]:
    ha, ta = body(f"{sys.argv[1]}/{name}/recording.bin")
    hb, tb = body(f"{sys.argv[2]}/{name}/recording.bin")
    print(name, "ticks", "same" if ta==tb else "DIFF", len(ta), "bytes; header", "same" if ha==hb else "differs")
    ok &= ta==tb
sys.exit(0 if ok else 1)
