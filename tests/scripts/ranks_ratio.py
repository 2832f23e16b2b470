#!/usr/bin/env python3
"""One and two ranks of one or more builds, alternated: the wall time of a scene and the ratio.

    python tests/scripts/ranks_ratio.py ROUNDS SCENE LABEL:BIN_DIR [LABEL:BIN_DIR ...]

Each round runs SCENE with every build (BIN_DIR holds coupler-node, solid-node and a fluid-node
built with `--features mpi`) on each rank count of RANKS (default "1,2"), the builds and the
rank counts in reversed order every other round, and reads `wall_s` from summary.json. Prints
each run, then per build and rank count the median [min-max] of the rounds, and per build the
ratio of the one-rank median to the two-rank one (docs/mpi.md's tables). Runs go to
OUT (default /tmp/ranks_ratio).
"""
import sys, os, subprocess, json, statistics
R=int(sys.argv[1]); scene=sys.argv[2]; bins=[a.split(':') for a in sys.argv[3:]]
ranks=[int(x) for x in os.environ.get('RANKS','1,2').split(',')]
env=dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT='1', OMPI_ALLOW_RUN_AS_ROOT_CONFIRM='1')
res={}
for r in range(R):
    order=bins if r%2==0 else bins[::-1]
    for k in (ranks if r%2==0 else ranks[::-1]):
        for lab,d in order:
            out=os.path.join(os.environ.get('OUT', '/tmp/ranks_ratio'), f'{lab}-{k}')
            cmd=[f'{d}/coupler-node','-q','run',scene,'--out',out,'--overwrite']
            if k>1: cmd+=['--fluid-ranks',str(k)]
            p=subprocess.run(cmd,capture_output=True,text=True,env=env)
            if p.returncode: print('FAIL',lab,k,p.stderr[-500:]); continue
            w=json.load(open(out+'/summary.json'))['wall_s']
            res.setdefault((lab,k),[]).append(w)
            print(f'round {r} {lab} ranks {k}: {w:.3f}', flush=True)
for (lab,k),v in sorted(res.items()):
    print(f'{lab} ranks {k}: median {statistics.median(v):.3f} [{min(v):.3f}-{max(v):.3f}] n={len(v)}')
for lab,_ in bins:
    if (lab,1) in res and (lab,2) in res:
        print(f'{lab}: ratio of medians {statistics.median(res[(lab,1)])/statistics.median(res[(lab,2)]):.3f}')
