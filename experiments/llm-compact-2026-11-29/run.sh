#!/usr/bin/env bash
# llm.answer_format: compact against full, the scene of docs/llm.md (layout seed 3, preset assist3d, the 2,858-asset
# Sweet Home 3D + procedural catalog), fake endpoint at 2 s + 0.02 s per answer token (50 tokens/s), then at a fixed 2 s.
cd "$(dirname "$0")/../.."; source .venv/bin/activate
C=${CATALOG:?the Sweet Home 3D + procedural catalog}; OUT=${OUT:-$(dirname "$0")}
date -u
python scripts/bench_llm_planning.py --assets $C --latency 2 --token-s 0.02 --modes serial,concurrent,batched --on-top-batch 8 \
  --answer-formats full,compact --json > $OUT/token-s-0.02.json
date -u
python scripts/bench_llm_planning.py --assets $C --latency 2 --modes serial,concurrent --answer-formats full,compact --json > $OUT/fixed-2s.json
date -u; echo DONE
