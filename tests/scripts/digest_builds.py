#!/usr/bin/env python3
"""Same bits from two builds: runs each scene with the binaries of two builds and compares every
recorded payload and every output file.

    python tests/scripts/digest_builds.py BIN_A BIN_B STEPS SCENE...

BIN_A and BIN_B hold coupler-node, fluid-node and solid-node. Each scene runs STEPS steps
(`run.max_steps`) with `record = "all"` and checkpoints every 2 steps, once with each build; then
the payloads of every recorded channel but /diagnostics (its JSON carries timings), hashed per
channel in record order, and every file of the output folder but summary.json (wall times) are
compared. Prints SAME or DIFF (the first keys that differ) per scene, and ALL SAME at the end;
a run that fails counts as a difference.

Environment: FR=k runs the fluid on k MPI ranks (`--fluid-ranks`, needs fluid-node built with
`--features mpi` and mpirun); CELLS=n sets `fluid.cells` to n on every axis; SET='sec.key=value;...'
sets more keys (for example SET='fluid.decomposition=[1, 2, 2];fluid.ranks=4'); OUT=DIR puts the
runs there (default /tmp/digest_builds). Needs a Python with the `mcap` package (.ci/venv has it).
"""
import sys, os, subprocess, hashlib, re, tomllib, json
from mcap.reader import make_reader
A, B, steps = sys.argv[1], sys.argv[2], int(sys.argv[3])
scenes = sys.argv[4:]
FR = os.environ.get('FR'); CELLS = os.environ.get('CELLS'); SET = os.environ.get('SET', '')
root = os.environ.get('OUT', '/tmp/digest_builds')
os.makedirs(root, exist_ok=True)
env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT='1', OMPI_ALLOW_RUN_AS_ROOT_CONFIRM='1')

def edit(text):
    lines = text.split('\n')
    def setkey(section, key, val):
        nonlocal lines
        # find section header
        idx = None
        for i, l in enumerate(lines):
            if l.strip() == f'[{section}]':
                idx = i; break
        if idx is None:
            lines += [f'[{section}]', f'{key} = {val}']; return
        j = idx + 1
        while j < len(lines) and not lines[j].strip().startswith('['):
            if re.match(rf'\s*{re.escape(key)}\s*=', lines[j]):
                lines[j] = f'{key} = {val}'; return
            j += 1
        lines.insert(idx + 1, f'{key} = {val}')
    setkey('run', 'max_steps', str(steps))
    setkey('run', 'record', '"all"')
    setkey('run', 'checkpoint_every', '2')
    if CELLS:
        d = tomllib.loads(text)['fluid']['cells']
        setkey('fluid', 'cells', '[' + ', '.join([CELLS] * len(d)) + ']')
    for kv in filter(None, SET.split(';')):
        k, v = kv.split('=', 1); s, k = k.split('.', 1)
        setkey(s.strip(), k.strip(), v.strip())
    return '\n'.join(lines)

def run(bindir, scene, tag):
    out = f'{root}/{os.path.basename(scene)[:-5]}-{tag}'
    sc = f'{root}/{os.path.basename(scene)}'
    open(sc, 'w').write(edit(open(scene).read()))
    subprocess.run(['rm', '-rf', out])
    cmd = [f'{bindir}/coupler-node', '-q', 'run', sc, '--out', out, '--overwrite']
    if FR: cmd += ['--fluid-ranks', FR]
    r = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if r.returncode != 0:
        print(f'  {tag}: rc {r.returncode}: {r.stderr[-800:]}')
        return None
    return out

def digests(out):
    d = {}
    if out is None: return {'FAILED': 'x'}
    with open(f'{out}/exchange.mcap', 'rb') as f:
        for sch, ch, m in make_reader(f).iter_messages(log_time_order=False):
            if ch.topic == '/diagnostics': continue
            h = d.setdefault('ch:' + ch.topic, hashlib.sha256())
            h.update(m.data)
    for fn in sorted(os.listdir(out)):
        if fn in ('summary.json', 'exchange.mcap', 'scene.toml'): continue
        p = f'{out}/{fn}'
        if os.path.isfile(p):
            d['file:' + fn] = hashlib.sha256(open(p, 'rb').read())
    return {k: v.hexdigest() for k, v in d.items()}

allsame = True
for sc in scenes:
    a = digests(run(A, sc, 'a')); b = digests(run(B, sc, 'b'))
    if 'FAILED' in a or 'FAILED' in b: print(os.path.basename(sc), 'FAILED'); allsame = False; continue
    diff = [k for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]
    nch = sum(1 for k in a if k.startswith('ch:'))
    print(f'{os.path.basename(sc)}: {"SAME" if not diff else "DIFF " + str(diff[:8])} ({nch} channels, {len(a)-nch} files)')
    allsame &= not diff
print('ALL SAME' if allsame else 'SOME DIFFER')
