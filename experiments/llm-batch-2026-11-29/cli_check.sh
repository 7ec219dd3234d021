#!/usr/bin/env bash
# Issue 14's acceptance through the command itself: `assist3d layout` (seed 3, paper settings) against a local
# fake endpoint answering in 2 s (scripts/bench_llm_planning.py's server), serial / concurrent / batched, then
# the batched run again from its cache with the endpoint gone. Usage: cli_check.sh CATALOG [SCRATCH]
set -euo pipefail
CAT=$1; S=${2:-$(mktemp -d)}; mkdir -p "$S"
cd "$(dirname "$0")/../.."
cat > "$S/serve.py" <<'PY'
import sys, time
sys.path.insert(0, "scripts")
from bench_llm_planning import LatencyServer
srv = LatencyServer(2.0, 0, 45.0)
open(sys.argv[1], "w").write(srv.url)
time.sleep(3600)
PY
python "$S/serve.py" "$S/url" & SP=$!; trap 'kill $SP 2>/dev/null || true' EXIT
sleep 3; URL=$(cat "$S/url")
run() {  # mode plan_concurrently on_top_batch base_url out
  printf "layout:\n  planner: llm\nllm:\n  concurrency: 8\n  plan_concurrently: %s\n  on_top_batch: %s\n  cache_dir: %s\n  retries: 0\n  max_failures: 1000\n" \
    "$2" "$3" "$S/cache-$1" > "$S/$1.yaml"
  /usr/bin/time -f "$5 wall %e s" env OPENAI_API_KEY=dummy assist3d layout --seed 3 --assets "$CAT" --config "$S/$1.yaml" \
    --llm-base-url "$4" --llm-model bench-fake --out "$S/out-$5" --no-glb --json > /dev/null 2> "$S/$5.err"; tail -1 "$S/$5.err"
}
run serial false 1 "$URL" serial
run concurrent true 1 "$URL" concurrent
run batched true 8 "$URL" batched
kill $SP
run batched true 8 http://127.0.0.1:9/v1 batched-cache
python - "$S" <<'PY'
import json, sys
S = sys.argv[1]
lays = {m: json.load(open(f"{S}/out-{m}/layout.json")) for m in ("serial", "concurrent", "batched", "batched-cache")}
for m, l in lays.items():
    print(m, "instances", len(l["instances"]), "llm_calls", l["stats"].get("llm_calls"), "cache_hits", l["stats"].get("cache_hits"))
same = {m: json.dumps(l["instances"], sort_keys=True) == json.dumps(lays["serial"]["instances"], sort_keys=True) for m, l in lays.items()}
print("same instances as serial:", same)
PY
