"""Each generator's two seeds: value, geometry_diversity_sd, geometry_diversity_se, and the gap against the se."""
import json
import math
import sys

rows = {tuple(k.split("/")[-2:]): v for k, v in json.load(open(sys.argv[1])).items()}
print("| generator | seed 0: value, sd, se | seed 1: value, sd, se | gap | sqrt(se0^2 + se1^2) | gap / that |")
print("| --- | --- | --- | ---: | ---: | ---: |")
for g in ("assist3d", "randomrooms", "holodeck-style", "no-context"):
    a, b = rows[("cmp50s0", g)], rows[("cmp50s1", g)]
    gap = abs(a["geometry_diversity"] - b["geometry_diversity"])
    comb = math.hypot(a["geometry_diversity_se"], b["geometry_diversity_se"])
    cell = lambda r: f"{r['geometry_diversity']:.4f}, {r['geometry_diversity_sd']:.4f}, {r['geometry_diversity_se']:.4f}"  # noqa: E731
    print(f"| {g} | {cell(a)} | {cell(b)} | {gap:.4f} | {comb:.4f} | {gap / comb:.2f} |")
