"""Paired per-scan comparison of two recipes (bench/evaluation/compare.py)."""

from __future__ import annotations

import pytest

from assist3d.bench.evaluation.compare import mean_over_runs, paired_comparison, recipe_comparison


def test_paired_comparison_counts_wins_and_resamples_rooms_not_scans():
    a = {"scene0001_00": 0.2, "scene0001_01": 0.2, "scene0001_02": 0.2, "scene0002_00": 0.5}
    # B gains 0.3 on the three rescans of one room and loses 0.1 on the other room
    b = {"scene0001_00": 0.5, "scene0001_01": 0.5, "scene0001_02": 0.5, "scene0002_00": 0.4}
    c = paired_comparison(a, b, draws=500)
    assert (c.scans, c.rooms, c.higher, c.lower, c.equal) == (4, 2, 3, 1, 0)
    assert c.mean_diff == pytest.approx((0.9 - 0.1) / 4)
    assert c.per_room == pytest.approx({"scene0001": 0.3, "scene0002": -0.1})
    # two rooms: a draw holds room 1 twice (+0.3), room 2 twice (-0.1) or both (+0.2); the interval
    # spans the room-level outcomes, which scan resampling (three of four scans agree) would narrow
    assert c.ci95[0] == pytest.approx(-0.1) and c.ci95[1] == pytest.approx(0.3)
    assert paired_comparison(a, b, draws=500).ci95 == c.ci95  # seeded


def test_recipe_comparison_holds_the_seed_spread_that_the_paired_interval_leaves_out():
    scans = [f"scene{r:04d}_0{k}" for r in range(1, 5) for k in range(2)]
    a = [{s: 0.3 for s in scans}] * 2
    # B's two seeds: one 0.2 above A on every scan, one 0.2 below; their mean equals A everywhere
    b = [{s: 0.5 for s in scans}, {s: 0.1 for s in scans}]
    r = recipe_comparison(a, b, draws=1000)
    assert r.paired.mean_diff == pytest.approx(0.0) and r.paired.ci95 == (0.0, 0.0)  # rooms alone: no doubt
    assert r.ci95[0] == pytest.approx(-0.2) and r.ci95[1] == pytest.approx(0.2)  # one seed drawn twice
    assert r.runs_a == [0.3, 0.3] and r.runs_b == [0.5, 0.1]
    assert r.to_json()["ci95_rooms_and_runs"] == [-0.2, 0.2] and r.to_json()["mean_diff"] == pytest.approx(0.0)
    with pytest.raises(ValueError, match="different scans"):
        recipe_comparison(a, [{scans[0]: 0.1}])
    # two variants of the same two models (run k is model k on both sides), figures varying by room
    # and by model, B equal to A on every scan: rooms drawn alike for both sides, and with paired
    # runs the models too, so no draw can show a difference; drawing the runs apart would
    model = [{s: 0.1 * int(s[5:9]) + 0.3 * k for s in scans} for k in range(2)]
    same = recipe_comparison(model, [dict(m) for m in model], draws=500, paired_runs=True)
    assert same.paired.ci95 == (0.0, 0.0) and same.ci95 == (0.0, 0.0)
    apart = recipe_comparison(model, [dict(m) for m in model], draws=500)
    assert apart.ci95[0] < -0.1 and apart.ci95[1] > 0.1
    with pytest.raises(ValueError, match="as many runs"):
        recipe_comparison(model, model[:1], paired_runs=True)


def test_room_of_finds_the_scannet_room_anywhere_in_a_scan_id():
    from assist3d.bench.evaluation.compare import room_of

    assert room_of("scene0006_01") == room_of("scene0006_00") == "scene0006"
    assert room_of("scannet_scene0451_01") == "scene0451" != room_of("scannet_scene0452_00")
    assert room_of("office_a_scan2") == "office_a_"  # other names: the first 9 characters
    assert room_of("scene00012_00") == "scene0001"  # not a ScanNet name: the first 9 characters


def test_paired_comparison_refuses_different_scans_and_non_finite_figures():
    with pytest.raises(ValueError, match="different scans: scene0002_00"):
        paired_comparison({"scene0001_00": 0.1}, {"scene0001_00": 0.2, "scene0002_00": 0.3})
    with pytest.raises(ValueError, match="not finite"):
        paired_comparison({"scene0001_00": float("nan")}, {"scene0001_00": 0.2})
    with pytest.raises(ValueError, match="no scans"):
        paired_comparison({}, {})


def test_mean_over_runs_averages_each_scan_and_checks_the_scans_match():
    assert mean_over_runs([{"x": 0.1, "y": 0.4}, {"x": 0.3, "y": 0.0}]) == pytest.approx({"x": 0.2, "y": 0.2})
    with pytest.raises(ValueError, match="different scans"):
        mean_over_runs([{"x": 0.1}, {"y": 0.2}])


def test_compare_probes_reads_probe_folders_and_hybrid_eval_rows(load_script, tmp_path):
    import json

    cp = load_script("compare_probes")
    probe = tmp_path / "probe"
    for seed, v in ((0, 0.1), (1, 0.3)):
        (probe / f"seed_{seed}").mkdir(parents=True)
        (probe / f"seed_{seed}" / "result.json").write_text(json.dumps(
            {"per_scene": {"scene0001_00": {"AP50": v}, "scene0002_00": {"AP50": 2 * v}},
             "hybrid": {"per_scene": {"scene0001_00": {"AP50": v + 0.5}, "scene0002_00": {"AP50": v}}}}))
    (probe / "seed_2").mkdir()  # unfinished seed: no result.json, not counted
    assert cp.per_scan(str(probe), "AP50") == (pytest.approx({"scene0001_00": 0.2, "scene0002_00": 0.4}), 2)
    assert cp.per_scan(f"{probe}:learned", "AP50") == cp.per_scan(str(probe), "AP50")
    assert cp.per_scan(f"{probe}:hybrid", "AP50") == (pytest.approx({"scene0001_00": 0.7, "scene0002_00": 0.2}), 2)
    with pytest.raises(SystemExit, match="not 'geometric'"):
        cp.per_scan(f"{probe}:geometric", "AP50")
    (probe / "seed_0" / "result.json").write_text(json.dumps({"per_scene": {"scene0001_00": {"AP50": 0.1}}}))
    with pytest.raises(SystemExit, match="run the probe again with --hybrid"):
        cp.per_scan(f"{probe}:hybrid", "AP50")
    row = [{"scans": {"scene0001_00": {"AP50": 0.5}}}, {"scans": {"scene0451_01": {"AP50": 0.1}}}]
    hybrid = tmp_path / "h.json"
    hybrid.write_text(json.dumps({"models": {"a.pt": {"hybrid": row}, "b.pt": {"hybrid": row}}}))
    assert cp.per_scan(f"{hybrid}:hybrid", "AP50") == (pytest.approx({"scene0001_00": 0.5, "scene0451_01": 0.1}), 2)
    with pytest.raises(SystemExit, match="no row 'learned'"):
        cp.per_scan(f"{hybrid}:learned", "AP50")
    with pytest.raises(SystemExit, match="no seed_"):
        cp.per_scan(str(probe / "seed_2"), "AP50")  # a folder without finished seeds
    with pytest.raises(SystemExit, match="neither a probe folder nor FILE.json:ROW"):
        cp.per_scan(str(tmp_path / "missing.json:hybrid"), "AP50")
