#!/usr/bin/env bash
# Screenshots of the MLflow UI on a main job's tracking store, taken with headless Chromium.
#
#   bash scripts/screenshots_mlflow.sh [STORE] [PORT] [OUT]
#
# STORE  a folder holding the job's mlflow.db (SQLite) and mlruns/ (default: the checkout);
#        mlflow.db is copied to a temporary folder first, so the store is only read
# PORT   the port `mlflow server` listens on, on 127.0.0.1 only (default: 5055); Chromium's
#        DevTools port is PORT + 1, also on 127.0.0.1
# OUT    where the PNGs go (default: docs/screenshots)
#
# Writes, each a window 1400 wide shrunk to 256 colours:
#   OUT/mlflow_experiments.png  the experiment list, named `<study>/<what>` (1400x620)
#   OUT/mlflow_run.png          the run `selection1-rf` of the first `.../cv_clean`
#                               experiment: its metrics, parameters and tags (1400x1000)
#   OUT/mlflow_compare.png      `selection1-rf` and `selection3-rf` of the first two
#                               `.../cv_clean` experiments (the paper and bench
#                               acquisitions) compared: the parameters that differ and
#                               the first metrics, fold by fold (1400x1150)
# Needs `chromium` (Debian: apt-get install chromium) and the checkout's .venv (mlflow,
# its aiohttp, pillow). The server and the browser are stopped on exit, whatever happens.
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
STORE=$(cd "${1:-$ROOT}" && pwd)
PORT=${2:-5055}
OUT=${3:-$ROOT/docs/screenshots}
PY=${PYTHON:-$ROOT/.venv/bin/python}
MLFLOW=${MLFLOW:-$ROOT/.venv/bin/mlflow}
CHROMIUM=${CHROMIUM:-chromium}
URL="http://127.0.0.1:$PORT"
DEVTOOLS="http://127.0.0.1:$((PORT + 1))"

[[ -f $STORE/mlflow.db && -d $STORE/mlruns ]] || {
  echo "screenshots_mlflow: $STORE holds no mlflow.db and mlruns/" >&2; exit 2; }
command -v "$CHROMIUM" >/dev/null || {
  echo "screenshots_mlflow: no $CHROMIUM (apt-get install chromium)" >&2; exit 2; }
for u in "$URL" "$DEVTOOLS"; do
  if curl -s -o /dev/null "$u"; then
    echo "screenshots_mlflow: something already answers on $u" >&2; exit 2
  fi
done
mkdir -p "$OUT"
TMP=$(mktemp -d)
SERVER="" BROWSER=""
cleanup() {  # each runs in its own process group: the kill reaches its children too
  for p in $BROWSER $SERVER; do
    kill -- "-$p" 2>/dev/null || true
    wait "$p" 2>/dev/null || true
  done
  rm -rf "$TMP"
}
trap cleanup EXIT

cp "$STORE/mlflow.db" "$TMP/mlflow.db"
setsid "$MLFLOW" server --host 127.0.0.1 --port "$PORT" --workers 1 \
  --backend-store-uri "sqlite:///$TMP/mlflow.db" \
  --default-artifact-root "$STORE/mlruns" >"$TMP/server.log" 2>&1 &
SERVER=$!
setsid "$CHROMIUM" --headless=new --no-sandbox --disable-gpu --hide-scrollbars \
  --no-first-run --user-data-dir="$TMP/chromium" --window-size=1400,1000 \
  --remote-debugging-address=127.0.0.1 --remote-debugging-port="$((PORT + 1))" \
  about:blank >"$TMP/chromium.log" 2>&1 &
BROWSER=$!

for _ in $(seq 120); do  # at most 2 min
  curl -sf -o /dev/null "$URL/health" && break
  kill -0 "$SERVER" 2>/dev/null || { cat "$TMP/server.log" >&2; exit 1; }
  sleep 1
done
curl -sf -o /dev/null "$URL/health" || {
  echo "screenshots_mlflow: the server did not answer in 2 min" >&2
  tail -20 "$TMP/server.log" >&2; exit 1; }

# Chromium over the DevTools protocol (aiohttp comes with mlflow): each page loaded fresh,
# the assistant panel kept closed, shot once its content is there (then 3 s for the rest)
"$PY" - "$TMP/mlflow.db" "$URL" "$DEVTOOLS" "$OUT" <<'PYEOF'
import asyncio
import base64
import json
import sqlite3
import sys
import time
import urllib.parse
from pathlib import Path

import aiohttp
from PIL import Image

db, url, devtools, out = sqlite3.connect(sys.argv[1]), sys.argv[2], sys.argv[3], Path(sys.argv[4])
ML = "workflowType=machine_learning"  # the model-training views, not the GenAI ones


def fail(msg: str):
    sys.exit(f"screenshots_mlflow: {msg}")


names = [n for (n,) in db.execute("SELECT name FROM experiments WHERE name LIKE '%/%' AND "
                                  "lifecycle_stage = 'active'")]
exps = [e for (e,) in db.execute("SELECT experiment_id FROM experiments WHERE name LIKE "
                                 "'%/cv_clean' ORDER BY experiment_id LIMIT 2")]
if not exps:
    fail("no '<study>/<data set>/cv_clean' experiment in the store")


def run(exp: str, name: str) -> str:
    row = db.execute("SELECT run_uuid FROM runs WHERE experiment_id = ? AND name = ? AND "
                     "lifecycle_stage = 'active' ORDER BY start_time DESC LIMIT 1",
                     (exp, name)).fetchone()
    return row[0] if row else fail(f"no run '{name}' in experiment {exp}")


pick = [run(e, n) for e in exps for n in ("selection1-rf", "selection3-rf")]
compare = urllib.parse.urlencode({"runs": json.dumps(pick),
                                  "experiments": json.dumps([str(e) for e in exps])})
METRICS = "[...document.querySelectorAll('h4')].find(e => e.textContent.startsWith('Metrics ('))"
VISUALS = ("[...document.querySelectorAll('[role=button]')]"
           ".find(e => e.textContent.trim() === 'Visualizations')")
DIFF = "document.querySelector('[aria-label=\"Parameters - Show diff only\"]')"
#: file, window height, address, JavaScript true once the page is drawn, JavaScript then run
PAGES = (
    ("mlflow_experiments.png", 620, f"{url}/#/experiments?{ML}",
     " && ".join(f"document.body.innerText.includes({json.dumps(n)})" for n in names), ""),
    ("mlflow_run.png", 1000, f"{url}/#/experiments/{exps[0]}/runs/{pick[0]}?{ML}",
     f"!!{METRICS}", f"{METRICS}.scrollIntoView({{block: 'start'}})"),
    ("mlflow_compare.png", 1150, f"{url}/#/compare-runs?{compare}&{ML}",
     f"document.body.innerText.includes('Comparing {len(pick)} Runs') && !!{DIFF}",
     f"{VISUALS}.click(); {DIFF}.click()"),
)


async def shoot() -> None:
    async with aiohttp.ClientSession() as http:
        for _ in range(150):  # at most 30 s for Chromium to start
            try:
                async with http.get(f"{devtools}/json/list") as r:
                    tab = next(p for p in await r.json() if p["type"] == "page")
                break
            except (aiohttp.ClientError, StopIteration):
                await asyncio.sleep(0.2)
        else:
            fail(f"no Chromium answers on {devtools}")
        async with http.ws_connect(tab["webSocketDebuggerUrl"], max_msg_size=0) as ws:
            ids = iter(range(1, 1 << 30))

            async def call(method: str, **params):
                n = next(ids)
                await ws.send_json({"id": n, "method": method, "params": params})
                async for msg in ws:
                    d = json.loads(msg.data)
                    if d.get("id") == n:
                        return d["result"] if "error" not in d else fail(f"{method}: {d}")

            async def js(expression: str):
                r = await call("Runtime.evaluate", expression=expression, returnByValue=True)
                return r["result"].get("value")

            async def png(file: Path) -> None:
                shot = await call("Page.captureScreenshot", format="png")
                file.write_bytes(base64.b64decode(shot["data"]))

            await call("Page.navigate", url=f"{url}/health")  # the UI's origin: its storage
            await asyncio.sleep(1)
            await js("localStorage.setItem('mlflow.assistant.panelOpen_v1', 'false'); "
                     "localStorage.setItem('mlflow.assistant.fab.autoOpenedOnFirstLoad_v1', "
                     "'true')")
            for name, height, address, ready, then in PAGES:
                await call("Emulation.setDeviceMetricsOverride", width=1400, height=height,
                           deviceScaleFactor=1, mobile=False)
                await call("Page.navigate", url="about:blank")
                await call("Page.navigate", url=address)
                deadline = time.monotonic() + 60
                while not await js(f"!!document.body && ({ready})"):
                    if time.monotonic() > deadline:
                        await png(out / name)
                        fail(f"{address} not drawn in 60 s; as it stood: {out / name}")
                    await asyncio.sleep(0.5)
                await asyncio.sleep(1)
                if then:
                    await js(then)
                await asyncio.sleep(3)
                await png(out / name)
                im = Image.open(out / name).convert("RGB")  # 256 colours: a third the size
                im.quantize(256, method=Image.Quantize.MEDIANCUT).save(out / name,
                                                                       optimize=True)
                print(f"{out / name}: {im.width}x{im.height}, "
                      f"{(out / name).stat().st_size // 1024} KB")


asyncio.run(shoot())
PYEOF
