#!/usr/bin/env python3
"""The 18 splits of the paper-003 3-D beam's 4 cuboids into 6 tetrahedra each, as scenes.

Each cuboid [1.85715, 2.14285] x [y_k, y_k + 1/7] x [0.85715, 1.14285] (k = 0..3, y_0 = -1/14)
is cut by the square diagonal A-C of its x-z section into two triangular prisms along y,
and each prism into three tetrahedra by the staircase rule of an order of its three corners.
Orders that agree on the shared quad A-C give a conforming mesh: 18 distinct splits (the
other square diagonal gives their mirror images in z). Two of them are Kuhn splits
(prism-01 is scenes/clamped-beam-3d-unweighted.toml). Everything else comes from the
base scene; t_end is cut to 0.4 s, and every top tetrahedron whose centroid starts at
x = 2 m gets a probe tip_N (tip_0 the highest).

    python3 docs/beam-3d-unweighted/splits.py scenes/clamped-beam-3d-unweighted.toml OUT_DIR
    target/release/coupler-node run OUT_DIR/prism-NN.toml --out OUT_DIR/prism-NN -q
"""
import itertools
import re
import sys
from pathlib import Path

XL, XH, ZL, ZH = 1.85715, 2.14285, 0.85715, 1.14285
A, B, C, D = (XL, ZL), (XH, ZL), (XH, ZH), (XL, ZH)
NAME = {A: "A", B: "B", C: "C", D: "D"}
PRISMS = [(A, B, C), (A, C, D)]


def prism_tets(order, ylo, yhi):
    a, b, c = order
    p = lambda q, y: (q[0], y, q[1])
    return [
        [p(a, ylo), p(b, ylo), p(c, ylo), p(c, yhi)],
        [p(a, ylo), p(b, ylo), p(b, yhi), p(c, yhi)],
        [p(a, ylo), p(a, yhi), p(b, yhi), p(c, yhi)],
    ]


def splits():
    seen = []
    for order in itertools.permutations([A, B, C, D]):
        key = tuple(tuple(sorted(tri, key=order.index)) for tri in PRISMS)
        if key not in seen:
            seen.append(key)
    return seen


def main(base_path, out_dir):
    base = Path(base_path).read_text()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for n, key in enumerate(splits()):
        tets = []
        for k in range(4):
            ylo = -1 / 14 + k / 7
            for order in key:
                tets += prism_tets(order, ylo, ylo + 1 / 7)
        name = f"prism-{n:02d}"
        i = base.index("shape = { particles = [")
        j = base.index("] }\n", i) + 4
        body = ["shape = { particles = ["]
        body += ["  { vertices = [%s] }," % ", ".join("[%r, %r, %r]" % v for v in t) for t in tets]
        s = base[:i] + "\n".join(body) + "\n] }\n" + base[j:]
        s = re.sub(r'^name = ".*"', f'name = "{name}"', s, count=1, flags=re.M)
        s = s.replace("t_end = 1.0", "t_end = 0.4")
        s = s[: s.index("[[output.probes]]")]
        tops = [tuple(sum(v[a] for v in t) / 4 for a in range(3)) for t in tets[18:]]
        tips = sorted((c for c in tops if abs(c[0] - 2.0) < 1e-9), key=lambda c: -c[1])
        for m, c in enumerate(tips):
            s += f'[[output.probes]]\nname = "tip_{m}"\nparticle_at = [{c[0]!r}, {c[1]!r}, {c[2]!r}]\n\n'
        (out / f"{name}.toml").write_text(s.rstrip("\n") + "\n")
        print(name, " ".join("".join(NAME[q] for q in o) for o in key))


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
