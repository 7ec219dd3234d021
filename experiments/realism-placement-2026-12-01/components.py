"""Coverage, free space and height behind outcome.md (seed-0 sets and the real dev scans).
Usage: python components.py PRESETS_DIR RANDOM_DIR  (the P and D folders of run.sh)."""
import sys

import numpy as np

from assist3d.bench.metrics.realism import stats_of_dataset

P, D = sys.argv[1], sys.argv[2]
sets = [("ASSIST-3D", f"assist3d:{P}/assist3d"), ("ASSIST-3D random", f"assist3d:{D}/assist3d-random-s0"),
        ("Holodeck-style", f"assist3d:{P}/holodeck-style"), ("Holodeck-style random", f"assist3d:{D}/holodeck-style-random-s0"),
        ("RandomRooms-style", f"assist3d:{P}/randomrooms"), ("real dev scans", "array:../shared/data/real/dev")]
for name, spec in sets:
    s = stats_of_dataset(spec).arrays()
    print(f"{name}: coverage min/median/max {np.round(np.percentile(s['coverage'], [0, 50, 100]), 2).tolist()}, "
          f"median free ring {np.median(s['free_space']):.2f}, share of objects > 5 cm up {np.mean(s['height'] > 0.05):.2f}")
