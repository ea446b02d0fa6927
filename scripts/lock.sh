#!/usr/bin/env bash
# Refresh requirements-lock.txt: every package that scripts/quickstart.sh installs (the
# dependencies and the `dev` and `docs` extras of pyproject.toml, torch's CPU wheel among
# them), each pinned with its sha256 hashes (pip-tools' pip-compile --generate-hashes,
# Python 3.11).
# pyproject.toml keeps its ranges for library users; this file is for the set-up.
#   bash scripts/lock.sh                  # keep the current pins where pyproject.toml allows
#   bash scripts/lock.sh --upgrade        # the newest releases pyproject.toml allows
#   bash scripts/lock.sh -P numpy         # move one package only (pip-compile's -P)
# pip-tools runs in a throwaway venv. torch must resolve to the CPU wheel 2.13.0+cpu (here
# from pip's find-links, /opt/wheels); its hash is then that wheel's own. A plain
# torch==2.13.0 from PyPI is a CUDA build: the script refuses such a lock.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
py="${PYTHON:-python3.11}"
"$py" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))' || {
    echo "lock.sh: needs Python 3.11 (set PYTHON=...)" >&2; exit 2; }
tools="$(mktemp -d)"
trap 'rm -rf "$tools"' EXIT
"$py" -m venv "$tools/venv"
"$tools/venv/bin/python" -m pip install -q "pip==26.3" "pip-tools==7.6.2" 2>/dev/null
CUSTOM_COMPILE_COMMAND="bash scripts/lock.sh" "$tools/venv/bin/pip-compile" -q \
    --extra dev --extra docs --generate-hashes --allow-unsafe --strip-extras \
    --no-emit-index-url --no-emit-find-links \
    --output-file requirements-lock.txt "$@" pyproject.toml \
    2> >(grep -v "is ignored: it is neither a file nor a directory" >&2)
grep -q '^torch==2\.13\.0+cpu ' requirements-lock.txt || {
    echo "lock.sh: torch is not pinned to the CPU wheel 2.13.0+cpu in requirements-lock.txt" \
         "(is its wheel in pip's find-links?)" >&2; exit 1; }
echo "requirements-lock.txt: $(grep -c '^[A-Za-z0-9]' requirements-lock.txt) packages pinned"
