"""A run's folder (what `coupler-node run SCENE --out DIR` writes) as numpy arrays."""

import csv
import json
import os
import shutil
import subprocess

import numpy as np

from . import vtk


def read_csv(path):
    """A CSV file with a header line as a numpy structured array (one field per column;
    numbers as float64 or int64, text as str), read with the standard `csv` module (quoted
    fields, CRLF). A file with a header and no rows gives an empty array with the header's
    fields; a row of another length than the header is an error naming it."""
    with open(path, encoding="utf-8", newline="") as f:
        lines = [row for row in csv.reader(f) if row]
    header, rows = [h.strip() for h in lines[0]], lines[1:]
    for i, row in enumerate(rows):
        if len(row) != len(header):
            raise ValueError(f"{path}: row {i + 2} has {len(row)} values for {len(header)} columns")
    columns = list(zip(*rows)) if rows else [() for _ in header]
    fields = []
    for name, col in zip(header, columns):
        for kind in (np.int64, np.float64):
            try:
                values = np.array(col, dtype=kind) if col else np.array([], dtype=np.float64)
                break
            except ValueError:
                continue
        else:
            values = np.array(col, dtype=str)
        fields.append((name, values))
    out = np.empty(len(rows), dtype=[(n, v.dtype) for n, v in fields])
    for name, values in fields:
        out[name] = values
    return out


class Field:
    """One output of a node: `arrays` (dict of numpy arrays, VTK order: x fastest), and for an
    image (`fluid`) its `cells` (nx, ny, nz), `origin` and `spacing` [m]; for polydata
    (`solid`) its `points` (n, 3) [m]. `field["p"]` is `field.arrays["p"]`."""

    def __init__(self, arrays, cells=None, origin=None, spacing=None, points=None, t=None):
        self.arrays = arrays
        self.cells = cells
        self.origin = origin
        self.spacing = spacing
        self.points = points
        self.t = t

    def __getitem__(self, name):
        return self.arrays[name]

    def keys(self):
        return self.arrays.keys()

    def grid(self, name):
        """An image's cell array `name` shaped (nz, ny, nx, ...) without its axes of one cell:
        (ny, nx) for a 2-D fluid."""
        nx, ny, nz = self.cells
        a = self.arrays[name]
        shape = (nz, ny, nx) + a.shape[1:]
        return a.reshape(shape).squeeze(axis=tuple(i for i, n in enumerate((nz, ny, nx)) if n == 1))

    def centres(self):
        """An image's cell centres along x, y, z [m] (three 1-D arrays)."""
        return [self.origin[a] + (np.arange(self.cells[a]) + 0.5) * self.spacing[a] for a in range(3)]


class Run:
    """A run's folder; see `open_run`."""

    def __init__(self, path, coupler=None):
        self.path = os.fspath(path)
        if not os.path.isfile(self._file("summary.json")):
            raise FileNotFoundError(f"{self.path}: no summary.json (not a run's folder?)")
        with open(self._file("summary.json"), encoding="utf-8") as f:
            self.summary = json.load(f)
        self.ledger = read_csv(self._file("ledger.csv"))
        outputs = self._file("outputs.csv")
        self.outputs = read_csv(outputs) if os.path.isfile(outputs) else None
        self._coupler = coupler

    def _file(self, name):
        return os.path.join(self.path, name)

    def _time(self, k):
        if self.outputs is None:
            return None
        t = self.outputs["t"][self.outputs["k"] == k]
        return float(t[0]) if len(t) else None

    def fluid(self, k):
        """The fluid at output `k`: `fluid_k.vti` (cell arrays rho, p, alpha, velocity,
        vtkGhostType), else the columns of `fluid_k.csv` (covered cells left out)."""
        vti = self._file(f"fluid_{k}.vti")
        if os.path.isfile(vti):
            f = vtk.read(vti)
            ext = [int(v) for v in f.dataset["WholeExtent"].split()]
            cells = tuple(max(ext[2 * a + 1], 1) for a in range(3))
            origin = [float(v) for v in f.dataset["Origin"].split()]
            spacing = [float(v) for v in f.dataset["Spacing"].split()]
            arrays = {n: f.array("CellData", n) for n in f.names("CellData")}
            return Field(arrays, cells=cells, origin=origin, spacing=spacing, t=self._time(k))
        table = read_csv(self._file(f"fluid_{k}.csv"))
        return Field({n: table[n] for n in table.dtype.names}, t=self._time(k))

    def solid(self, k):
        """The particles at output `k`: `particles_k.vtp` (points = centres; id, velocity,
        angular_velocity, theta or orientation, sigma_n), else the columns of `solid_k.csv`."""
        vtp = self._file(f"particles_{k}.vtp")
        if os.path.isfile(vtp):
            f = vtk.read(vtp)
            arrays = {n: f.array("PointData", n) for n in f.names("PointData")}
            return Field(arrays, points=f.array("Points", "Points"), t=self._time(k))
        table = read_csv(self._file(f"solid_{k}.csv"))
        return Field({n: table[n] for n in table.dtype.names}, t=self._time(k))

    def faces(self, k, kind="solid"):
        """The raw decoded `KIND_k.vtp` (`solid`: the particles' faces, `wet`: the wet
        surface) as a `vtk.VtkFile`."""
        return vtk.read(self._file(f"{kind}_{k}.vtp"))

    def probe(self, name):
        """`probe_NAME.csv` as a structured array."""
        return read_csv(self._file(f"probe_{name}.csv"))

    def record(self):
        """The path of the record, `exchange.mcap`."""
        return self._file("exchange.mcap")

    def diagnostics(self):
        """The record's `/diagnostics` channel: one dict per step, in order."""
        from mcap.reader import make_reader

        out = []
        with open(self.record(), "rb") as f:
            for _schema, _channel, message in make_reader(f).iter_messages(topics=["/diagnostics"]):
                out.append(json.loads(message.data))
        return out

    def coupler(self):
        """The `coupler-node` binary: the one given to `open_run`, $COSIM_COUPLER, the one on
        PATH, or target/release/coupler-node above the run's folder."""
        if self._coupler:
            return self._coupler
        if os.environ.get("COSIM_COUPLER"):
            return os.environ["COSIM_COUPLER"]
        found = shutil.which("coupler-node")
        if found:
            return found
        d = os.path.abspath(self.path)
        while True:
            candidate = os.path.join(d, "target", "release", "coupler-node")
            if os.path.isfile(candidate):
                return candidate
            parent = os.path.dirname(d)
            if parent == d:
                raise FileNotFoundError("no coupler-node: pass coupler= to open_run or set COSIM_COUPLER")
            d = parent

    def exchange(self, step, whole=True):
        """Step `step`'s exchanged messages, as `coupler-node inspect RECORD --step N --export
        json` gives them: a list of dicts with `topic`, `sequence`, `kind` and `fields` (the
        message's fields; arrays as lists, made numpy arrays here).

        The solid sends a step's trials after the first as the particles that changed
        (`changed_only`, their numbers in `particles`); with `whole` (the default) each of those
        is put back onto the step's first trial, as the coupler does, so every `SolidState`
        holds every particle; `whole=False` gives the messages as recorded."""
        out = subprocess.run(
            [self.coupler(), "inspect", self.record(), "--step", str(step), "--export", "json"],
            check=True, capture_output=True,
        )
        doc = json.loads(out.stdout)
        for m in doc["messages"]:
            m["fields"] = _arrays(m["fields"])
        if whole:
            _whole_trials(doc["messages"])
        return doc["messages"]


_PER_PARTICLE = ("position", "orientation", "velocity", "angular_velocity", "diameter")


def _whole_trials(messages):
    """Puts each `changed_only` SolidState back onto the first whole one of its topic before it
    (the step's first trial), in place, as `SolidState::merged_onto` does."""
    first = {}
    for m in sorted(messages, key=lambda m: (m["topic"], m["sequence"])):
        if m["kind"] != "SolidState":
            continue
        f = m["fields"]
        if not f.get("changed_only"):
            first[m["topic"]] = f
            continue
        base = first.get(m["topic"])
        if base is None:
            raise ValueError(f"{m['topic']} #{m['sequence']}: changes without the step's first trial")
        ids = np.asarray(f["particles"], dtype=np.int64)
        n = len(base["diameter"])
        for key in _PER_PARTICLE:
            whole = np.array(base[key], dtype=np.float64).reshape(n, -1)
            if len(ids):
                whole[ids] = np.asarray(f[key], dtype=np.float64).reshape(len(ids), -1)
            f[key] = whole.reshape(-1)
        f["particles"] = np.array([], dtype=np.int64)
        f["changed_only"] = False


def _arrays(value):
    """Lists of numbers in `value` made numpy arrays (recursively)."""
    if isinstance(value, dict):
        return {k: _arrays(v) for k, v in value.items()}
    if isinstance(value, list):
        if value and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
            return np.array(value)
        return [_arrays(v) for v in value]
    return value


def open_run(path, coupler=None):
    """Opens the run in folder `path` (`coupler`: the `coupler-node` binary for `exchange`)."""
    return Run(path, coupler=coupler)
