#!/usr/bin/env python3
"""Conforming splits of the paper-003 3-D beam's 4 cuboids into 6 tetrahedra each, as scenes.

Each cuboid [1.85715, 2.14285] x [y_k, y_k + 1/7] x [0.85715, 1.14285] (k = 0..3,
y_0 = -1/14) is cut into two triangular prisms along an axis (y, z or x) by a diagonal of
its section, and each prism into three tetrahedra by the staircase rule of an order of its
three corners. Odd layers may repeat the even layers' split or mirror it in y. A split is
kept when the layers' faces match on every plane y = y_k (a conforming mesh) and neither it
nor its mirror image in z was met before:

    prism-NN      along y, one section diagonal (the other gives the z-mirrors): 18 splits,
                  the two Kuhn splits among them (prism-01 is the shipped scene's split,
                  its tetrahedra listed in another order)
    split-z-NN    along z                                                       20 splits
    split-x-NN    along x                                                       10 splits
    split-yalt-NN along y, odd layers mirrored in y (the others are already above)  4 splits

Everything else comes from the base scene; t_end is cut to 0.4 s, and every top tetrahedron
whose centroid starts at x = 2 m gets a probe tip_N (tip_0 the highest).

    python3 docs/beam-3d-unweighted/splits.py scenes/clamped-beam-3d-unweighted.toml OUT_DIR
    target/release/coupler-node run OUT_DIR/prism-01.toml --out OUT_DIR/prism-01 -q
"""
import itertools
import re
import sys
from pathlib import Path

XL, XH, ZL, ZH = 1.85715, 2.14285, 0.85715, 1.14285
CORNER = {"A": (0, 0), "B": (1, 0), "C": (1, 1), "D": (0, 1)}


def layer_y(k):
    lo = -1 / 14 + k / 7
    return lo, lo + 1 / 7


def layer_tets(axis, diag, order, k, mirror):
    """The 6 tetrahedra of layer k: section corners (u, v), extrusion coordinate w."""
    ylo, yhi = layer_y(k)
    if axis == "y":
        u, v, w = (XL, XH), (ZL, ZH), ((yhi, ylo) if mirror else (ylo, yhi))
        point = lambda a, b, c: (a, c, b)
    elif axis == "z":
        u, v, w = (XL, XH), ((yhi, ylo) if mirror else (ylo, yhi)), (ZL, ZH)
        point = lambda a, b, c: (a, b, c)
    else:
        u, v, w = (ZL, ZH), ((yhi, ylo) if mirror else (ylo, yhi)), (XL, XH)
        point = lambda a, b, c: (c, b, a)
    prisms = [("A", "B", "C"), ("A", "C", "D")] if diag == "AC" else [("A", "B", "D"), ("B", "C", "D")]
    at = lambda name, iw: point(u[CORNER[name][0]], v[CORNER[name][1]], w[iw])
    tets = []
    for tri in prisms:
        a, b, c = sorted(tri, key=order.index)
        tets += [
            [at(a, 0), at(b, 0), at(c, 0), at(c, 1)],
            [at(a, 0), at(b, 0), at(b, 1), at(c, 1)],
            [at(a, 0), at(a, 1), at(b, 1), at(c, 1)],
        ]
    return tets


def key(tets):
    return frozenset(frozenset(tuple(round(c, 9) for c in p) for p in t) for t in tets)


def z_mirror(tets):
    return [[(p[0], p[1], 2.0 - p[2]) for p in t] for t in tets]


def faces_on(tets, y):
    return {
        frozenset(tuple(round(c, 9) for c in p) for p in t if abs(p[1] - y) < 1e-9)
        for t in tets
        if sum(abs(p[1] - y) < 1e-9 for p in t) == 3
    }


def conforming(tets):
    for k in range(1, 4):
        y = layer_y(k)[0]
        below, above = faces_on(tets[(k - 1) * 6 : k * 6], y), faces_on(tets[k * 6 : (k + 1) * 6], y)
        if below != above or len(below) != 2:
            return False
    return True


def splits():
    """(name, rule, tetrahedra) of every kept split; split-z and split-x share one count."""
    families = [
        ("prism", "y", ("AC",), (False,)),
        ("split", "z", ("AC", "BD"), (False, True)),
        ("split", "x", ("AC", "BD"), (False, True)),
        ("split-yalt", "y", ("AC", "BD"), (True,)),
    ]
    seen, count = set(), {}
    for family, axis, diagonals, alternates in families:
        for diag in diagonals:
            for order in itertools.permutations("ABCD"):
                for alternate in alternates:
                    tets = []
                    for k in range(4):
                        tets += layer_tets(axis, diag, order, k, alternate and k % 2 == 1)
                    if not conforming(tets) or key(tets) in seen:
                        continue
                    seen.add(key(tets))
                    seen.add(key(z_mirror(tets)))
                    n = count.get(family, 0)
                    count[family] = n + 1
                    name = f"split-{axis}-{n:02d}" if family == "split" else f"{family}-{n:02d}"
                    rule = f"{axis} {diag} {''.join(order)}" + (" alternate" if alternate else "")
                    yield name, rule, tets


def main(base_path, out_dir):
    base = Path(base_path).read_text()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for name, label, tets in splits():
        i = base.index("shape = { particles = [")
        j = base.index("] }\n", i) + 4
        body = ["shape = { particles = ["]
        body += ["  { vertices = [%s] }," % ", ".join("[%r, %r, %r]" % p for p in t) for t in tets]
        s = base[:i] + "\n".join(body) + "\n] }\n" + base[j:]
        s = re.sub(r'^name = ".*"', f'name = "{name}"', s, count=1, flags=re.M)
        s = s.replace("t_end = 1.0", "t_end = 0.4")
        s = s[: s.index("[[output.probes]]")]
        tops = [tuple(sum(p[a] for p in t) / 4 for a in range(3)) for t in tets[18:]]
        tips = sorted((c for c in tops if abs(c[0] - 2.0) < 1e-9), key=lambda c: -c[1])
        for m, c in enumerate(tips):
            s += f'[[output.probes]]\nname = "tip_{m}"\nparticle_at = [{c[0]!r}, {c[1]!r}, {c[2]!r}]\n\n'
        (out / f"{name}.toml").write_text(s.rstrip("\n") + "\n")
        print(name, label)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
