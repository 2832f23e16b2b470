#!/usr/bin/env python3
"""Bench binaries of `fv_blast3d` alternated: the best and the median stepping rate of each.

    python tests/scripts/bench_best.py ROUNDS BIN [BIN ...] [KEY=VALUE ...]

Each BIN is a copy of the `fv_blast3d` bench binary of one build (`cargo bench -p fluid-node
--no-default-features --bench fv_blast3d --no-run` prints its path); KEY=VALUE sets its
environment (ISA, THREADS, CELLS, STEPS). Each round runs every binary once, in reversed order
every other round, and reads the rate of the stepping loop it prints (cell updates/s). On a
shared host whose speed moves from run to run, the best of many runs is the steadiest figure,
and the median says how typical it is (docs/performance.md).
"""
import sys, os, subprocess, re, statistics

R = int(sys.argv[1])
bins = [a for a in sys.argv[2:] if '=' not in a]
env = dict(os.environ)
for kv in (a for a in sys.argv[2:] if '=' in a):
    k, v = kv.split('=', 1)
    env[k] = v
res = {b: [] for b in bins}
for r in range(R):
    for b in (bins if r % 2 == 0 else bins[::-1]):
        out = subprocess.run([b], env=env, capture_output=True, text=True).stdout
        m = re.search(r'([0-9.e+]+) cell updates/s', out)
        if not m:
            sys.exit(f'{b} printed no rate:\n{out[-500:]}')
        res[b].append(float(m.group(1)) / 1e6)
for b in bins:
    v = sorted(res[b])
    print(f'{b}: best {v[-1]:.3f}, median {statistics.median(v):.3f} M cell updates/s ({R} runs)')
