"""Fingerprint of what the generator produces, for restructuring steps that must change no byte.

Generates a 3-scene dataset (preset assist3d, seed 0) and 12 layouts (presets assist3d,
randomrooms, holodeck-style and no-context; seeds 0, 1, 2) and prints one SHA-256 per scene, per
layout and for the whole, with wall-clock timings left out (they differ between any two runs).
Run it before and after a change and compare the last line:

    python scripts/structure_hashes.py [--assets DIR] [--json]

The dataset hash covers every array, layout.json, meta.json, config.yaml and manifest.json.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import tempfile
from pathlib import Path

from assist3d.assets import open_catalog
from assist3d.config import parse_config
from assist3d.pipeline import generate_dataset
from assist3d.config.presets import apply_preset
from assist3d.scene.layout import build_layout
from assist3d.testing import SCENE_ARRAYS

PRESETS = ("assist3d", "randomrooms", "holodeck-style", "no-context")
SEEDS = (0, 1, 2)
# the search's wall-clock safety net raised far above its node budget, so machine load cannot
# change a layout (the default 4 s can cut a search short on a busy machine)
UNTIMED_LAYOUT = {"group_budget_s": 600.0}


def untimed(obj):
    """``obj`` without wall-clock or CPU timings (keys naming seconds or timing)."""
    if isinstance(obj, dict):
        return {k: untimed(v) for k, v in obj.items() if "seconds" not in k and k not in ("timing", "timings")}
    if isinstance(obj, list):
        return [untimed(v) for v in obj]
    return obj


def json_digest(obj) -> str:
    return hashlib.sha256(json.dumps(untimed(obj), sort_keys=True).encode()).hexdigest()


def dataset_hashes(assets: str | None) -> dict[str, str]:
    cfg = parse_config({"seed": 0, "assets": {"library": assets}, "layout": UNTIMED_LAYOUT})
    out: dict[str, str] = {}
    with tempfile.TemporaryDirectory(prefix="assist3d-hash-") as tmp:
        generate_dataset(cfg, tmp, range(3))
        root = Path(tmp)
        for d in sorted(root.glob("scene_*")):
            h = hashlib.sha256()
            for name in SCENE_ARRAYS:
                h.update((d / name).read_bytes())
            meta = json.loads((d / "meta.json").read_text())
            meta["files"].pop("layout.json")  # its checksum covers the layout's timings
            h.update(json_digest(meta).encode())
            h.update(json_digest(json.loads((d / "layout.json").read_text())).encode())
            out[d.name] = h.hexdigest()
        out["config.yaml"] = hashlib.sha256((root / "config.yaml").read_bytes()).hexdigest()
        out["manifest.json"] = json_digest(json.loads((root / "manifest.json").read_text()))
    return out


def layout_hashes(assets: str | None) -> dict[str, str]:
    out: dict[str, str] = {}
    catalog = None
    for preset in PRESETS:
        cfg = apply_preset({"assets": {"library": assets}, "layout": UNTIMED_LAYOUT}, preset)
        if catalog is None:  # spelled out, so the script also runs against older checkouts
            a = cfg.assets
            catalog = open_catalog(a.library, procedural_count=a.procedural_count, procedural_seed=a.procedural_seed)
        for seed in SEEDS:
            layout = build_layout(catalog, cfg, seed, scene_index=seed)
            out[f"{preset}/{seed}"] = json_digest(layout.to_json())
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--assets", default=None, help="asset catalog folder (default: as `assist3d generate`)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    res = {"dataset": dataset_hashes(args.assets), "layouts": layout_hashes(args.assets)}
    res["all"] = hashlib.sha256(json.dumps(res, sort_keys=True).encode()).hexdigest()
    if args.json:
        print(json.dumps(res, indent=1))
        return
    for group in ("dataset", "layouts"):
        for k, v in res[group].items():
            print(f"{group:8s} {k:22s} {v[:16]}")
    print(f"all      {res['all']}")


if __name__ == "__main__":
    main()
