#!/usr/bin/env bash
# Prepare a bare GPU machine (no network, its own Python with torch) to run the segmenter's probe:
# install the carried wheels (.whl/: pydantic and its needs), unpack the carried real scans
# (.devdata/real.tar.xz) and every packed training set (.devdata/NAME.npz.xz, scripts/pack_scenes.py)
# under $DATA (default /tmp/d): $DATA/dev, $DATA/scannet_scene0451_01.npy, $DATA/NAME.
# SRC (default $PWD/src) names the package source put on PYTHONPATH (e.g. a frozen copy, carried).
# Source it: `. scripts/device_setup.sh`, then run `python3 -m assist3d probe ... --device cuda`.
set -e
DATA=${DATA:-/tmp/d}
if [[ ${WHEELS:-1} == 1 ]] && compgen -G ".whl/*.whl" > /dev/null; then
  python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl
  export PYTHONPATH=/tmp/site:${SRC:-$PWD/src}
else
  export PYTHONPATH=${SRC:-$PWD/src}
fi
export PYTHONUNBUFFERED=1
mkdir -p "$DATA"
[[ -f .devdata/real.tar.xz && ! -d "$DATA/dev" ]] && tar -C "$DATA" -xJf .devdata/real.tar.xz
for f in .devdata/*.npz.xz; do
  [[ -e "$f" ]] || continue
  name=$(basename "$f" .npz.xz)
  [[ -d "$DATA/$name" ]] || python3 scripts/pack_scenes.py unpack "$f" "$DATA/$name"
done
set +e
