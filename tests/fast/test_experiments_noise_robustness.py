"""experiments/tools/noise_robustness.py: the denoising measured (and not adopted) in experiments/fidelity-log.md, "Noisy scans"."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("torch")


@pytest.mark.slow
def test_denoise_thins_a_noisy_surface_moving_points_along_its_normal_only(load_script):
    denoise_points = load_script("noise_robustness").denoise_points

    rng = np.random.default_rng(0)
    plane = np.c_[rng.uniform(0, 2, (40_000, 2)), np.zeros(40_000)].astype(np.float32)
    noisy = plane.copy()
    noisy[:, 2] += rng.normal(0, 0.005, len(noisy)).astype(np.float32)
    out = denoise_points(noisy)
    assert out.dtype == np.float32 and out.shape == noisy.shape
    assert out[:, 2].std() < noisy[:, 2].std() / 3  # 5 mm of noise -> under 1.7 mm
    assert np.abs(out[:, :2] - noisy[:, :2]).max() < 0.005  # moved (almost) along the normal only
    assert np.array_equal(denoise_points(noisy), out)  # deterministic
    # the same surface sampled ten times as densely is denoised alike (cells, not points, are fitted)
    dense = np.repeat(noisy, 10, 0)
    assert np.allclose(denoise_points(dense)[::10], out, atol=1e-6)
    # a point with fewer than three occupied cells within the radius stays where it is
    lone = np.array([[0, 0, 0], [0.5, 0, 0], [0, 0.5, 0.01]], np.float32)
    assert np.array_equal(denoise_points(lone), lone)
    one_cell = np.array([[0.001, 0.001, 0.0], [0.002, 0.001, 0.0], [0.001, 0.002, 0.001]], np.float32)
    assert np.array_equal(denoise_points(one_cell), one_cell)  # one cell: no plane, no crash


def test_summary_keeps_plane_refits_apart_and_skips_mask_change_files(load_script, tmp_path, capsys):
    """--summarize over a folder of results: the same (sigma, method, eval) made with and without plane
    refits are two rows, never averaged together; a --mask-change file (no AP rows) is skipped with a note."""
    import json

    summarize_files = load_script("noise_robustness").summarize_files
    spec = "array:/x/dev"

    def write(name: str, seed: int, refine: int | dict | None, ap50: float) -> None:
        d = {"eval": [spec], "seed": seed,
             "rows": [{"sigma": 0.001, "denoise": False, "method": "hybrid", spec: {"AP50": ap50, "AP25": 0.5}}]}
        if refine is not None:
            d["refine_planes"] = refine
        (tmp_path / name).write_text(json.dumps(d))

    write("a.json", 0, None, 0.20)  # written before --refine-planes: no refits
    write("b.json", 1, {"geometric": 2, "hybrid": 0}, 0.30)
    write("c.json", 0, {"geometric": 0, "hybrid": 2}, 0.90)
    write("d.json", 1, 2, 0.70)  # the first files with refits: one number for both methods
    (tmp_path / "change.json").write_text(json.dumps({"method": "hybrid", "eval": [spec]}))
    summarize_files(sorted(tmp_path.glob("*.json")))
    out = capsys.readouterr()
    rows = [line for line in out.out.splitlines() if line.startswith("| 0.001")]
    assert len(rows) == 2, out.out
    assert "| 0 | dev | 0.250 ± 0.071 |" in rows[0] and "0,1" in rows[0]
    assert "| 2 | dev | 0.800 ± 0.141 |" in rows[1] and "0,1" in rows[1]
    assert "change.json" in out.err and "skipped" in out.err
