#!/usr/bin/env bash
# The Python environment of the Python API (python/, docs/PYTHON.md): a
# virtual environment .venv at the top of the tree (Debian's Python is
# externally managed, PEP 668) with python/requirements.txt installed from
# PyPI. Idempotent: does nothing when .venv already holds those requirements.
# Prints nothing on success but what pip says on a first install.
set -euo pipefail
cd "$(dirname "$0")/.."
req=python/requirements.txt
stamp=.venv/.cellray-requirements
if [ -x .venv/bin/python ] && cmp -s "$req" "$stamp" 2>/dev/null; then exit 0; fi
python3 -m venv .venv
.venv/bin/python -m pip install -q --disable-pip-version-check -r "$req"
cp "$req" "$stamp"
