#!/usr/bin/env bash
# Set up .venv at the repo root if needed, then run the main job or the tests.
#   bash scripts/quickstart.sh main [hydra overrides...]   # the paper's full study
#   bash scripts/quickstart.sh test [pytest args...]       # the test suite
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
py="${PYTHON:-python3.11}"
command -v "$py" >/dev/null 2>&1 || py=python3
stamp=".venv/.installed-$(sha1sum pyproject.toml | cut -c1-12)"
if [ ! -f "$stamp" ]; then
    echo "== setting up .venv (once; a few minutes)"
    [ -x .venv/bin/python ] || "$py" -m venv .venv
    .venv/bin/python -m pip install -q --upgrade pip >/dev/null 2>&1 || true
    # the CPU wheel of torch first, so that nothing pulls a CUDA build
    .venv/bin/python -c "import torch" 2>/dev/null || .venv/bin/python -m pip install -q "torch==2.13.0"
    .venv/bin/python -m pip install -q -e ".[dev]"
    rm -f .venv/.installed-*
    touch "$stamp"
fi
what="${1:-}"
[ $# -gt 0 ] && shift
case "$what" in
    main) exec .venv/bin/swgsim-paper "$@" ;;
    test) exec .venv/bin/python -m pytest "$@" ;;
    *) echo "usage: bash scripts/quickstart.sh {main|test} [args...]" >&2; exit 2 ;;
esac
