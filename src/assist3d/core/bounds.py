"""Upper bounds of the numbers that size work or memory, and a fast feasibility estimate.

Options and config fields that size the work have documented bounds (``Field(le=...)`` in
:mod:`assist3d.config`, ``max=`` on command-line options, the constants here). Combinations that
each pass their bound can still be too large together (a 16384 x 16384 image from 100 x 360
views); :func:`check_render_memory` estimates the peak memory of rendering one scene from the
config alone and refuses before any work starts, with the estimate in the message.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

from .errors import ConfigError

__all__ = ["MAX_SCENES", "MAX_SCENE_INDEX", "MAX_WORKERS", "MAX_THREADS", "MAX_SEED", "render_memory_bytes",
           "machine_memory_bytes", "check_render_memory", "check_scene_indices", "gib"]

#: Scenes one command generates at most (a dataset can grow past it over several runs).
MAX_SCENES = 1_000_000
#: Largest scene index (scene folders are named ``scene_%06d``; 9 digits at most).
MAX_SCENE_INDEX = 999_999_999
#: Worker processes of any command.
MAX_WORKERS = 256
#: Threads of any command.
MAX_THREADS = 256
#: Seeds are 32-bit: 0 .. 2**32 - 1 (larger or negative seeds would silently alias smaller ones).
MAX_SEED = 2**32 - 1

#: Fraction of the machine's memory one scene's rendering may use per worker.
MEMORY_SHARE = 0.8
#: Bytes per pixel of the camera's ray directions, held once (float64 while built, float32 kept).
_BYTES_PER_PIXEL_FIXED = 36
#: Bytes per pixel of one view being cast (directions, origins, depth, face ids, hit points, voxel
#: keys and the ray caster's buffers); measured 213-241 B per pixel with 2 threads (4 views).
_BYTES_PER_PIXEL_IN_FLIGHT = 48
#: Bytes per point kept from a view until the views are merged (voxel key, point, face id).
_BYTES_PER_KEPT_POINT = 24
#: Bytes per point of the fused cloud and its arrays (coord, normal, colour, labels, write buffers).
_BYTES_PER_POINT = 40


def gib(n: float) -> str:
    """``n`` bytes as ``"1.5 GiB"`` (or TiB / MiB)."""
    for unit, size in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20)):
        if n >= size or unit == "MiB":
            return f"{n / size:,.1f} {unit}"
    return f"{n:.0f} B"  # pragma: no cover


def _surface_voxels(cfg) -> float:
    """Voxels on the surfaces of the largest room: floor, walls and as much again for objects."""
    r = cfg.room
    long_side = math.sqrt(r.area_max * r.aspect_max)
    perimeter = 2.0 * (long_side + r.area_max / long_side)
    surface = 3.0 * r.area_max + perimeter * r.height_max
    return surface / cfg.render.voxel_size ** 2


def render_memory_bytes(cfg) -> float:
    """Estimated peak memory (bytes) of rendering one scene of ``cfg`` (a GenerateConfig).

    Pixels x (fixed + views in flight) + views x points kept per view + the fused cloud; each
    view keeps at most one point per voxel of the room's surfaces (or per pixel, if fewer)."""
    rc = cfg.render
    pixels = float(rc.width) * float(rc.height)
    views = float(rc.vantage_points) * float(rc.views_per_point)
    in_flight = 2 * max(1, rc.threads) if rc.threads > 1 else 1
    kept_per_view = min(pixels, _surface_voxels(cfg))
    return (pixels * (_BYTES_PER_PIXEL_FIXED + _BYTES_PER_PIXEL_IN_FLIGHT * in_flight)
            + views * kept_per_view * _BYTES_PER_KEPT_POINT
            + min(views * kept_per_view, _surface_voxels(cfg)) * _BYTES_PER_POINT)


def _cgroup_limit() -> float | None:
    for p in (Path("/sys/fs/cgroup/memory.max"), Path("/sys/fs/cgroup/memory/memory.limit_in_bytes")):
        try:
            text = p.read_text().strip()
        except OSError:
            continue
        if text.isdigit() and int(text) < 2**60:
            return float(text)
    return None


def machine_memory_bytes() -> float | None:
    """Physical memory of this machine (or its cgroup limit, if smaller); None if unknown."""
    try:
        total = float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return None
    limit = _cgroup_limit()
    return min(total, limit) if limit else total


def check_render_memory(cfg, workers: int = 1, memory: float | None = None) -> float:
    """Refuse (ConfigError) a render config whose estimated peak memory, times ``workers``, is
    more than :data:`MEMORY_SHARE` of the machine's memory; returns the estimate per worker."""
    need = render_memory_bytes(cfg)
    have = machine_memory_bytes() if memory is None else memory
    if have is None or need * workers <= MEMORY_SHARE * have:
        return need
    rc = cfg.render
    views = rc.vantage_points * rc.views_per_point
    rays = float(rc.width) * rc.height * views
    per = f"{gib(need)} per worker x {workers} workers" if workers > 1 else gib(need)
    raise ConfigError(
        f"render: {rc.width} x {rc.height} px from {views} views ({rays:.1e} rays) at {rc.voxel_size} m voxels "
        f"needs about {per} of memory (estimate), more than {MEMORY_SHARE:.0%} of this machine's {gib(have)}; "
        f"lower render.width / render.height, render.vantage_points x render.views_per_point"
        + (" or --workers" if workers > 1 else "") + ", or raise render.voxel_size")


def check_scene_indices(indices: list[int], what: str = "scenes") -> None:
    """Refuse more than :data:`MAX_SCENES` scenes or an index past :data:`MAX_SCENE_INDEX`."""
    if len(indices) > MAX_SCENES:
        raise ConfigError(f"{what}: {len(indices):,} scenes in one run; at most {MAX_SCENES:,} (run it in parts)")
    bad = [i for i in indices if not 0 <= i <= MAX_SCENE_INDEX]
    if bad:
        raise ConfigError(f"{what}: scene index {bad[0]} outside 0..{MAX_SCENE_INDEX:,}")
