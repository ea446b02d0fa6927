#!/usr/bin/env bash
# Set up .venv at the repo root if needed, then run the main job, the tests or the docs.
#   bash scripts/quickstart.sh main [hydra overrides...]   # the paper's full study
#   bash scripts/quickstart.sh test [pytest args...]       # the test suite
#   bash scripts/quickstart.sh docs [sphinx-build args...] # the documentation site: offline,
#                                                          # warnings as errors, written to
#                                                          # docs/_build/html
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
py="${PYTHON:-python3.11}"
command -v "$py" >/dev/null 2>&1 || py=python3
# the set-up installs requirements-lock.txt (every package pinned with its hashes, torch's CPU
# wheel among them; `bash scripts/lock.sh` refreshes it), then the project without
# dependencies; it runs again when the lock or pyproject.toml changes
lock=requirements-lock.txt
stamp=".venv/.installed-$(cat "$lock" pyproject.toml | sha1sum | cut -c1-12)"
if [ ! -f "$stamp" ]; then
    echo "== setting up .venv (once; a few minutes)"
    [ -x .venv/bin/python ] || "$py" -m venv .venv
    .venv/bin/python -m pip install -q --upgrade pip >/dev/null 2>&1 || true
    # pip's notes go to a log, shown only when the install fails
    log=.venv/install.log
    if ! { .venv/bin/python -m pip install -q --require-hashes -r "$lock" &&
           .venv/bin/python -m pip install -q --no-deps -e .; } >"$log" 2>&1; then
        grep -v "is ignored: it is neither a file nor a directory" "$log" | tail -n 40 >&2
        echo "== set-up failed (the whole log: $log)" >&2
        exit 1
    fi
    # numba keeps compiled kernels beside their sources: compile them once here, so that the
    # first test run or study does not pay for it in each of its processes (about 25 s)
    .venv/bin/python scripts/warm_jit.py >>"$log" 2>&1 ||
        echo "== compiling the numba kernels failed (they compile on first use; log: $log)" >&2
    rm -f .venv/.installed-*
    touch "$stamp"
fi
what="${1:-}"
[ $# -gt 0 ] && shift
case "$what" in
    main) exec .venv/bin/swgsim-paper "$@" ;;
    test) exec .venv/bin/python -m pytest "$@" ;;
    # the API pages and the gallery are generated anew each time (docs/api,
    # docs/auto_examples); the examples run on the tiny presets
    docs) rm -rf docs/_build docs/api docs/auto_examples docs/sg_execution_times.rst
          MPLBACKEND=Agg exec .venv/bin/python -m sphinx -b html -W --keep-going -q \
              "$@" docs docs/_build/html ;;
    *) echo "usage: bash scripts/quickstart.sh {main|test|docs} [args...]" >&2; exit 2 ;;
esac
