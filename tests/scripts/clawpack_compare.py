#!/usr/bin/env python3
"""Side-by-side measurements against Clawpack 5.14 classic (issue 36's targets).

Run with the Python that has Clawpack (``pip install --no-build-isolation clawpack==5.14.0``
into a venv, as DEVELOPERS.md says), from the repository root, with release binaries built:

    python tests/scripts/clawpack_compare.py --bin target/release --out /tmp/claw [--part blast,sod]
        [--base OLD_BIN_DIR] [--reps 3]

1. 3-D blast (``scenes/blast-3d.toml``: box [0, 2]^3, walls, 64^3, to t = 0.1), whole process
   wall time: ours is ``coupler-node run`` of the scene (``run.threads`` 1 and 2, no record),
   Clawpack's a Python process that sets up PyClaw's ClawSolver3D (Fortran, Roe ``euler_3D``, MC
   limiter, ``cfl_desired`` 0.8, dimensional splitting, wall boundaries) and runs it without
   output. Cell-update rate = cells x steps / wall time, and per CPU-second (user + system time
   of the whole process tree, which a loaded machine disturbs less); the runs alternate.
2. Sod (``scenes/sod.toml``, t = 0.2): L1 error of the density against the exact cell averages
   against the solver's time, one thread, best of 3. Ours from ``fluid-node report
   work-precision`` (OSMP5 at the scene's CFL), Clawpack's ClawSolver1D (Roe with entropy fix
   ``euler_with_efix_1D``, MC limiter, ``cfl_desired`` 0.8) timed around ``claw.run()``. The
   time to reach an error is interpolated log-log between resolutions.

Prints the tables (markdown) and writes the raw rows to OUT/*.csv.
"""
import argparse
import json
import math
import os
import resource
import subprocess
import sys
import time

import numpy as np

GAMMA = 1.4


# ---------------------------------------------------------------- exact Riemann solution (Toro)
def exact_riemann_sampler(wl, wr, gamma=GAMMA):
    """Toro (2009) ch. 4: returns rho(s) for s = x/t of the Riemann problem wl | wr (rho, u, p)."""
    rl, ul, pl = wl
    rr, ur, pr = wr
    cl, cr = math.sqrt(gamma * pl / rl), math.sqrt(gamma * pr / rr)

    def f(p, rk, pk, ck):
        if p > pk:
            a, b = 2 / ((gamma + 1) * rk), (gamma - 1) / (gamma + 1) * pk
            return (p - pk) * math.sqrt(a / (p + b))
        return 2 * ck / (gamma - 1) * ((p / pk) ** ((gamma - 1) / (2 * gamma)) - 1)

    lo, hi = 1e-12, 10 * max(pl, pr) + 10
    g = lambda p: f(p, rl, pl, cl) + f(p, rr, pr, cr) + ur - ul
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if g(mid) < 0 else (lo, mid)
    ps = 0.5 * (lo + hi)
    us = 0.5 * (ul + ur) + 0.5 * (f(ps, rr, pr, cr) - f(ps, rl, pl, cl))

    def side(s, rk, uk, pk, ck, sign):
        # sign = -1 for the left wave, +1 for the right one (in the frame s * sign).
        gm = (gamma - 1) / (gamma + 1)
        if ps > pk:  # shock
            rs = rk * (ps / pk + gm) / (gm * ps / pk + 1)
            sk = uk + sign * ck * math.sqrt((gamma + 1) / (2 * gamma) * ps / pk + (gamma - 1) / (2 * gamma))
            return np.where(sign * (s - sk) > 0, rk, rs)
        rs = rk * (ps / pk) ** (1 / gamma)
        cs = ck * (ps / pk) ** ((gamma - 1) / (2 * gamma))
        head, tail = uk + sign * ck, us + sign * cs
        fan = rk * (2 / (gamma + 1) - sign * (gamma - 1) / ((gamma + 1) * ck) * (uk - s)) ** (2 / (gamma - 1))
        return np.where(sign * (s - head) > 0, rk, np.where(sign * (s - tail) > 0, fan, rs))

    def rho(s):
        return np.where(s < us, side(s, rl, ul, pl, cl, -1), side(s, rr, ur, pr, cr, 1))

    return rho


def exact_averages(n, t, x0=0.5, sub=None):
    """Cell averages of the Sod density on n cells of [0, 1] at time t (midpoint rule, `sub`
    points a cell: 4096 on 400 cells reads our OSMP5 run as the repository's exact averages do,
    6.0828e-4; 64 points read 6.057e-4)."""
    sub = sub or max(1024, 2 ** 21 // n)
    rho = exact_riemann_sampler((1.0, 0.0, 1.0), (0.125, 0.0, 0.1))
    dx = 1.0 / n
    xs = (np.arange(n)[:, None] + (np.arange(sub)[None, :] + 0.5) / sub) * dx
    return rho((xs - x0) / t).mean(axis=1)


# ---------------------------------------------------------------- Clawpack
def claw_sod(n, cfl=0.8, t_end=0.2):
    from clawpack import pyclaw, riemann

    solver = pyclaw.ClawSolver1D(riemann.euler_with_efix_1D)
    solver.kernel_language = "Fortran"
    solver.limiters = pyclaw.limiters.tvd.MC
    solver.cfl_desired, solver.cfl_max = cfl, 1.0
    solver.bc_lower[0] = solver.bc_upper[0] = pyclaw.BC.extrap
    domain = pyclaw.Domain([pyclaw.Dimension(0.0, 1.0, n, name="x")])
    state = pyclaw.State(domain, 3)
    state.problem_data["gamma"], state.problem_data["gamma1"] = GAMMA, GAMMA - 1
    state.problem_data["efix"] = True
    x = state.grid.x.centers
    left = x < 0.5
    state.q[0, :] = np.where(left, 1.0, 0.125)
    state.q[1, :] = 0.0
    state.q[2, :] = np.where(left, 1.0, 0.1) / (GAMMA - 1)
    claw = pyclaw.Controller()
    claw.tfinal, claw.solution, claw.solver = t_end, pyclaw.Solution(state, domain), solver
    claw.output_format, claw.keep_copy, claw.num_output_times = None, True, 1
    claw.verbosity = 0
    t0 = time.perf_counter()
    claw.run()
    wall = time.perf_counter() - t0
    rho = claw.frames[-1].state.q[0, :]
    l1 = float(np.abs(rho - exact_averages(n, t_end)).sum() / n)
    return wall, solver.status["numsteps"], l1


CLAW_BLAST = r"""
import time, sys
t0 = time.perf_counter()
import numpy as np
from clawpack import pyclaw, riemann
n = int(sys.argv[1])
solver = pyclaw.ClawSolver3D(riemann.euler_3D)
solver.dimensional_split = True
solver.limiters = pyclaw.limiters.tvd.MC
solver.cfl_desired, solver.cfl_max = 0.8, 1.0
solver.all_bcs = pyclaw.BC.wall
solver.dt_initial = 1e-4  # the default, 0.1, would start at Courant number ~10
dims = [pyclaw.Dimension(0.0, 2.0, n, name=a) for a in "xyz"]
domain = pyclaw.Domain(dims)
state = pyclaw.State(domain, 5)
state.problem_data["gamma"], state.problem_data["gamma1"] = 1.4, 0.4
X, Y, Z = state.grid.p_centers
ball = (X - 1.1) ** 2 + (Y - 1.0) ** 2 + (Z - 1.0) ** 2 < 0.1 ** 2
state.q[0] = np.where(ball, 8.0, 1.4)
state.q[1:4] = 0.0
state.q[4] = np.where(ball, 116.5, 1.0) / 0.4
claw = pyclaw.Controller()
claw.tfinal, claw.solution, claw.solver = 0.1, pyclaw.Solution(state, domain), solver
claw.output_format, claw.keep_copy, claw.num_output_times, claw.verbosity = None, False, 1, 0
claw.run()
print(solver.status["numsteps"], time.perf_counter() - t0)
"""


# ---------------------------------------------------------------- ours
def ours_blast(bin_dir, out, threads, n):
    text = open("scenes/blast-3d.toml").read()
    text = text.replace("t_end = 1.0", f"t_end = 0.1\nthreads = {threads}\nrecord = \"none\"")
    text = text.replace("cells = [64, 64, 64]", f"cells = [{n}, {n}, {n}]")
    scene = os.path.join(out, f"blast-{threads}t.toml")
    open(scene, "w").write(text)
    run_dir = os.path.join(out, f"blast-{threads}t-{time.time_ns()}")
    cmd = [os.path.join(bin_dir, "coupler-node"), "run", scene, "--out", run_dir, "-q"]
    wall, cpu, _ = timed(cmd)
    summary = json.load(open(os.path.join(run_dir, "summary.json")))
    return summary["steps"], wall, cpu


def timed(cmd):
    """Runs `cmd`; returns its wall time, the CPU time (user + system) of its process tree and
    its standard output."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    res = subprocess.run(cmd, check=True, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return wall, cpu, res.stdout


def part_blast(args):
    n, rows = args.blast_cells, []
    who_all = ["ours-1t", "ours-2t", "clawpack"]
    if args.base:
        who_all = ["base-1t", "base-2t"] + who_all
    for rep in range(args.reps):
        for who in who_all:
            if who == "clawpack":
                wall, cpu, out = timed([sys.executable, "-c", CLAW_BLAST, str(n)])
                steps = int(out.split()[0])
            else:
                bin_dir = args.bin if who.startswith("ours") else args.base
                steps, wall, cpu = ours_blast(bin_dir, args.out, int(who[5]), n)
            rows.append((who, rep, steps, wall, cpu, n ** 3 * steps / wall, n ** 3 * steps / cpu))
            print(f"blast {who} rep {rep}: {steps} steps, wall {wall:.2f} s, CPU {cpu:.2f} s, "
                  f"{rows[-1][5] / 1e6:.3f} M/s, {rows[-1][6] / 1e6:.3f} M per CPU-s", flush=True)
    with open(os.path.join(args.out, "blast.csv"), "w") as f:
        f.write("who,rep,steps,wall_s,cpu_s,rate_wall,rate_cpu\n")
        for r in rows:
            f.write(",".join(map(str, r)) + "\n")
    med = lambda w, k: float(np.median([r[k] for r in rows if r[0] == w]))
    print(f"\n| 3-D blast {n}^3 to t = 0.1, whole process | steps | wall [s] | CPU [s] | "
          f"M cell updates/s (wall) | per CPU-s | ratio to Clawpack (wall / CPU) |\n"
          "| --- | --- | --- | --- | --- | --- | --- |")
    for w in who_all:
        ws = [r for r in rows if r[0] == w]
        print(f"| {w} | {ws[0][2]} | {', '.join(f'{r[3]:.2f}' for r in ws)} | "
              f"{', '.join(f'{r[4]:.2f}' for r in ws)} | {med(w, 5) / 1e6:.3f} | "
              f"{med(w, 6) / 1e6:.3f} | {med(w, 5) / med('clawpack', 5):.2f} / "
              f"{med(w, 6) / med('clawpack', 6):.2f} |")


def time_at(rows, target):
    """Log-log interpolation of time against error between the resolutions that bracket
    `target` (rows: (cells, wall, l1), finer last)."""
    for (n0, w0, e0), (n1, w1, e1) in zip(rows, rows[1:]):
        if e0 >= target >= e1:
            s = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(w0) + s * (math.log(w1) - math.log(w0)))
    return float("nan")


def part_sod(args):
    cells = [int(c) for c in args.sod_cells.split(",")]
    # Best of 3 x reps runs for each (the report itself takes the best of 3), alternated.
    best_ours, best_claw, claw_rows = {}, {}, {}
    for rep in range(args.reps):
        wp = os.path.join(args.out, f"wp{rep}")
        subprocess.run([os.path.join(args.bin, "fluid-node"), "report", "work-precision",
                        "scenes/sod.toml", "--cells", args.sod_cells, "--orders", "5", "--out",
                        wp], check=True, capture_output=True)
        for line in open(os.path.join(wp, "work_precision_sod.csv")).read().split("\n")[1:]:
            w = line.split(",")
            if len(w) == 6 and w[0] == "osmp5":
                n, wall, l1 = int(w[2]), float(w[4]), float(w[5])
                best_ours[n] = (min(wall, best_ours.get(n, (wall,))[0]), l1)
        for n in cells:
            for _ in range(3):
                wall, steps, l1 = claw_sod(n)
                best_claw[n] = (min(wall, best_claw.get(n, (wall,))[0]), l1)
                claw_rows[n] = steps
    ours = [(n, best_ours[n][0], best_ours[n][1]) for n in cells]
    claw = [(n, best_claw[n][0], best_claw[n][1]) for n in cells]
    for n, w, e in claw:
        print(f"sod clawpack {n}: {claw_rows[n]} steps, best {w:.4f} s, L1 {e:.3e}", flush=True)
    with open(os.path.join(args.out, "sod.csv"), "w") as f:
        f.write("who,cells,wall_s,l1_rho\n")
        for who, rows in [("ours-osmp5", ours), ("clawpack", claw)]:
            for n, w, e in rows:
                f.write(f"{who},{n},{w},{e}\n")
    print("\n| cells | ours OSMP5: time [s], L1(ρ) | Clawpack: time [s], L1(ρ) |\n| --- | --- | --- |")
    for (n, w, e), (_, cw, ce) in zip(ours, claw):
        print(f"| {n} | {w:.4f}, {e:.3e} | {cw:.4f}, {ce:.3e} |")
    print("\n| L1(ρ) | ours [s] | Clawpack [s] | ours / Clawpack |\n| --- | --- | --- | --- |")
    for target in [1e-3, 5e-4, 3e-4]:
        a, b = time_at(ours, target), time_at(claw, target)
        print(f"| {target:.0e} | {a:.4f} | {b:.4f} | {a / b:.2f} |")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--bin", default="target/release")
    p.add_argument("--base", help="binaries of an earlier build, run beside ours in the blast")
    p.add_argument("--out", default="/tmp/clawpack-compare")
    p.add_argument("--part", default="blast,sod")
    p.add_argument("--reps", type=int, default=3)
    p.add_argument("--blast-cells", type=int, default=64)
    p.add_argument("--sod-cells", default="100,200,400,800,1600,3200")
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    if "blast" in args.part:
        part_blast(args)
    if "sod" in args.part:
        part_sod(args)


if __name__ == "__main__":
    main()
