"""scripts/noise_robustness.py: the denoising measured (and not adopted) in docs/fidelity.md, "Noisy scans"."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("torch")


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
