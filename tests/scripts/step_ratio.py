#!/usr/bin/env python3
"""One and two ranks of one build, alternated: the wall time of a scene and the time of a step.

    python tests/scripts/step_ratio.py ROUNDS SCENE BIN_DIR

BIN_DIR holds coupler-node, solid-node and a fluid-node built with `--features mpi`. Each round
runs SCENE on one rank and on two (in reversed order every other round); the scene must record
at least the diagnostics (`run.record = "diagnostics"`). A step's time is the median gap between
the publish times of consecutive `/diagnostics` messages from the fifth step on, so the start
(launch, initial surface, first steps) is left out. Prints each run, then the medians and their
ratios, and the medians of the rounds' ratios (docs/mpi.md). Runs go to OUT (default
/tmp/step_ratio). Needs a Python with the `mcap` package (.ci/venv has it).
"""
import sys, os, subprocess, json, statistics
from mcap.reader import make_reader

R, scene, bins = int(sys.argv[1]), sys.argv[2], sys.argv[3]
root = os.environ.get('OUT', '/tmp/step_ratio')
env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT='1', OMPI_ALLOW_RUN_AS_ROOT_CONFIRM='1')
res = {1: [], 2: []}
for r in range(R):
    for k in ((1, 2) if r % 2 == 0 else (2, 1)):
        out = os.path.join(root, f'ranks-{k}')
        cmd = [f'{bins}/coupler-node', '-q', 'run', scene, '--out', out, '--overwrite']
        if k > 1:
            cmd += ['--fluid-ranks', str(k)]
        p = subprocess.run(cmd, env=env, capture_output=True, text=True)
        if p.returncode:
            sys.exit(f'ranks {k} failed: {p.stderr[-500:]}')
        wall = json.load(open(os.path.join(out, 'summary.json')))['wall_s']
        with open(os.path.join(out, 'exchange.mcap'), 'rb') as f:
            times = [m.publish_time for _, _, m in make_reader(f).iter_messages(topics=['/diagnostics'])]
        if len(times) < 7:
            sys.exit(f'{len(times)} diagnostics messages: the scene needs at least 7 steps')
        step = statistics.median((b - a) / 1e6 for a, b in zip(times[4:], times[5:]))
        res[k].append((wall, step))
        print(f'round {r} ranks {k}: wall {wall:.3f} s, step {step:.1f} ms', flush=True)
med = lambda k, i: statistics.median(x[i] for x in res[k])
rounds = lambda i: statistics.median(a[i] / b[i] for a, b in zip(res[1], res[2]))
print(f'wall: {med(1, 0):.3f} s / {med(2, 0):.3f} s = {med(1, 0) / med(2, 0):.3f} '
      f'(median of the rounds\' ratios {rounds(0):.3f})')
print(f'step: {med(1, 1):.1f} ms / {med(2, 1):.1f} ms = {med(1, 1) / med(2, 1):.3f} '
      f'(median of the rounds\' ratios {rounds(1):.3f})')
