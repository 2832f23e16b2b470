#!/bin/sh
# Prints a Python interpreter that has the `mcap`, `vtk` and `numpy` packages, for the tests
# that read a record or the VTK files with independent readers and run the Python reader
# (python/, on PYTHONPATH): $COSIM_PYTHON when it is set; otherwise a venv in DIR (the tests
# pass their target's tmp folder) made on first use with python3 -m venv and pip install
# 'mcap==1.*' 'vtk==9.*' numpy.
# Tests running at once wait for each other on a lock, so the venv is made once.
set -eu
if [ -n "${COSIM_PYTHON:-}" ]; then
    printf '%s\n' "$COSIM_PYTHON"
    exit 0
fi
dir=${1:?usage: python-with-mcap.sh DIR}
mkdir -p "$dir"
venv="$dir/cosim-py"
exec 9>"$dir/cosim-py.lock"
flock 9
if ! "$venv/bin/python" -c 'import mcap, vtk, numpy' >/dev/null 2>&1; then
    python3 -m venv "$venv" >&2
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check 'mcap==1.*' 'vtk==9.*' numpy >&2
fi
printf '%s\n' "$venv/bin/python"
