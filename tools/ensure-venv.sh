#!/usr/bin/env bash
# Creates the project's virtual environment and installs the project (with its native
# hooks, the instruction counter, the store checker and the poll watch, which need a C compiler and the
# Python headers) and test tools.
set -euo pipefail
venv=${1:-.venv}
python=${PYTHON:-python3}
if ! "$python" -c 'import sys; sys.exit(sys.version_info < (3, 10))' 2>/dev/null; then
    echo "error: Python 3.10 or newer is needed as '$python'" >&2
    exit 1
fi
if [ ! -x "$venv/bin/python" ]; then
    echo "[setup] creating virtual environment $venv"
    "$python" -m venv "$venv"
fi
echo "[setup] installing the project into $venv"
"$venv/bin/python" -m pip install --quiet --upgrade pip >/dev/null
"$venv/bin/python" -m pip install --quiet -e '.[test]'
# Bytecode for what was installed: pip leaves none where PYTHONDONTWRITEBYTECODE is set, and then
# every run compiles numpy, PIL and unicorn's modules afresh (about 0.5 s a start)
"$venv/bin/python" -m compileall -q -j 0 "$venv/lib" >/dev/null \
    || echo "[setup] warning: some installed modules did not compile to bytecode (runs compile them as they start)" >&2
