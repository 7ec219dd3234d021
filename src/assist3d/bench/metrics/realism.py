"""Layout realism: how much a dataset's object arrangements look like those of real indoor scans.

The physical layout score (``plausibility.py``) checks that objects do not overlap, rest on
something and stay inside the room; random non-overlapping placement passes it. This score
instead compares *arrangement statistics* with those of real scans, measured the same way on any
point cloud with instance labels (generated or real), so it needs no layout file:

per object (an instance with at least ``MIN_VOXELS`` occupied 5 cm voxels)
  ``wall_distance``   horizontal distance from the object to the room's boundary, m
  ``misalignment``    angle between the object's main horizontal axis and the room's wall
                      directions, degrees in [0, 45] (objects without a clear main axis left out)
  ``height``          height of the object's lowest point above the floor, m
  ``neighbour``       horizontal distance to the nearest other object, m (0 when touching)
  ``free_space``      share of the 0.5 m ring around the object's footprint not covered by other
                      objects, in [0, 1]
per scene
  ``coverage``        share of the scan's floor-plan cells covered by objects, in [0, 1]

Objects must mean the same on both sides: generated scans label every placed object, so real scans
are read with every annotated object (``array:...?objects=annotated``, ``scannet:...?objects=annotated``),
not only the 18 classes of the ScanNet benchmark; the shipped reference is built that way, and every
dataset this module opens is read so (:func:`realism_spec`) unless its spec says ``objects=benchmark``.

Every cloud is first reduced to one point per 5 cm voxel, so a 50,000-vertex ScanNet subsample and
a dense rendered cloud give the same statistics for the same room. The room's boundary is the
outline of the scan's floor plan (10 cm cells occupied by any point, holes filled): it needs no
wall labels, which real scans do not all have (ScanNet leaves much clutter unannotated). The floor
is the 2nd percentile of the heights. The room's wall directions are the mode of the horizontal
orientations of the local neighbourhoods of the boundary cells and of the unlabelled points between
0.3 m and 2.0 m above the floor (modulo 90 degrees).

A dataset's statistics are compared with a reference's (by default the statistics of real ScanNet
scans shipped in ``resources/realism/scannet-dev.json``, made by ``scripts/realism_reference.py``;
or any labelled dataset) by the Kolmogorov-Smirnov distance per statistic, and

    layout_realism = 100 * (1 - mean KS distance over the six statistics)

so 100 means indistinguishable distributions. The KS distance needs no binning and no scale per
statistic, and it is bounded, so one statistic cannot dominate.

How much the score would move if the dataset's scenes were drawn again is estimated by
:func:`realism_standard_error`: the standard deviation of the score over resamplings of the dataset's
scenes with replacement (the reference held fixed), so two datasets whose scores differ by less than
about twice their combined standard error are not told apart by it.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from ...data import READERS, open_dataset, parse_spec
from ...core import reading
from ...core.errors import DataError, shown

VOXEL = 0.05
CELL = 0.10  # floor-plan grid for coverage and free space
RING = 0.5
MIN_VOXELS = 20
WALL_BAND = (0.3, 2.0)
ELONGATION = 1.3  # an object's main axis counts when its first horizontal extent is this much the second
OBJECT_STATS = ("wall_distance", "misalignment", "height", "neighbour", "free_space")
SCENE_STATS = ("coverage",)
STATS = OBJECT_STATS + SCENE_STATS
QUANTILES = 101
REFERENCE_VERSION = 1
BOOTSTRAP_DRAWS = 500  # scene resamplings behind a standard error
# room structure labelled as an object (a ceiling, walls from floor to ceiling): warned about, still counted
STRUCTURE_GAP = 0.1  # m: as close to the scan's top (99.5th height percentile), or to the floor
CEILING_LOW = 1.8  # m above the floor: a ceiling's lowest point ...
CEILING_SHARE = 0.25  # ... over at least this share of the floor-plan cells
WALLS_BOX_SHARE = 0.5  # floor to top over at least this share of the scan's horizontal bounding box ...
WALLS_HUG = 0.2  # m: ... with its points along the room's outline (median distance to it)

log = logging.getLogger(__name__)


@dataclass
class RealismStats:
    """Pooled arrangement statistics of a set of scenes (one list of values per statistic).

    ``per_scene[k]`` holds how many of ``values[k]`` each scene gave, in order, when the statistics
    were pooled scene by scene (:func:`scene_stats`, :meth:`add`); it is empty for a sample without
    scene structure (:func:`matched_sample`), which then has no standard error.
    """

    values: dict[str, list[float]] = field(default_factory=lambda: {k: [] for k in STATS})
    scenes: int = 0
    objects: int = 0
    per_scene: dict[str, list[int]] = field(default_factory=lambda: {k: [] for k in STATS})
    #: instance ids that look like room structure labelled as objects (see :func:`scene_stats`)
    structure_suspects: list[int] = field(default_factory=list)

    def add(self, other: "RealismStats") -> None:
        for k in STATS:
            self.values[k].extend(other.values[k])
            self.per_scene[k].extend(other.per_scene[k])
        self.structure_suspects.extend(other.structure_suspects)
        self.scenes += other.scenes
        self.objects += other.objects

    def has_scenes(self) -> bool:
        """Whether every value is attributed to one of ``scenes`` scenes (a standard error can be had)."""
        return all(len(self.per_scene[k]) == self.scenes and sum(self.per_scene[k]) == len(self.values[k])
                   for k in STATS)

    def arrays(self) -> dict[str, np.ndarray]:
        return {k: np.asarray(v, np.float64) for k, v in self.values.items()}


def _voxel_points(coord: np.ndarray, instance: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One point per occupied voxel (the voxel's mean) with its most frequent instance id (-1 = none)."""
    keys = np.floor(coord / VOXEL).astype(np.int64)
    keys -= keys.min(0)
    span = keys.max(0) + 1
    flat = (keys[:, 0] * span[1] + keys[:, 1]) * span[2] + keys[:, 2]  # one integer per voxel: a fast 1-D unique
    _, inv, counts = np.unique(flat, return_inverse=True, return_counts=True)
    inv = inv.reshape(-1)
    n = len(counts)
    centres = np.stack([np.bincount(inv, weights=coord[:, a], minlength=n) for a in range(3)], 1) / counts[:, None]
    # majority instance per voxel: sort by (voxel, instance) and take the longest run
    order = np.lexsort((instance, inv))
    v, ins = inv[order], instance[order]
    run_start = np.r_[True, (v[1:] != v[:-1]) | (ins[1:] != ins[:-1])]
    starts = np.flatnonzero(run_start)
    lengths = np.diff(np.r_[starts, len(v)])
    run_vox = v[starts]
    pick = np.lexsort((-lengths, run_vox))  # per voxel, its longest run first (ties: lowest id)
    first = np.unique(run_vox[pick], return_index=True)[1]
    best = np.full(n, -1, np.int64)
    best[run_vox[pick][first]] = ins[starts][pick][first]
    return centres, best


def _wall_directions(wall_xy: np.ndarray) -> float | None:
    """The room's wall orientation in [0, 90) degrees: mode of local line directions of wall points."""
    if len(wall_xy) < 20:
        return None
    tree = cKDTree(wall_xy)
    _, nb = tree.query(wall_xy, k=min(10, len(wall_xy)))
    pts = wall_xy[nb] - wall_xy[nb].mean(1, keepdims=True)
    cov = np.einsum("nki,nkj->nij", pts, pts)
    w, vec = np.linalg.eigh(cov)
    line = w[:, 1] > 4 * np.maximum(w[:, 0], 1e-12)  # clearly linear neighbourhoods
    if line.sum() < 10:
        return None
    d = vec[line, :, 1]
    ang = np.degrees(np.arctan2(d[:, 1], d[:, 0])) % 90.0
    hist, edges = np.histogram(ang, bins=90, range=(0, 90))
    hist = hist + np.roll(hist, 1) + np.roll(hist, -1)  # circular smoothing
    return float(edges[int(hist.argmax())] + 0.5)


def scene_stats(coord: np.ndarray, instance: np.ndarray, where: str = "a scene") -> RealismStats:
    """The statistics of one scene; ``instance`` (N,) with -1 (or any negative) for no object.

    Instances that look like room structure rather than objects are counted as objects all the same,
    listed in ``structure_suspects`` and warned about, naming ``where``: one that reaches the scan's
    top from at least ``CEILING_LOW`` above the floor over ``CEILING_SHARE`` of the floor plan (a
    ceiling), or that runs from the floor to the top over ``WALLS_BOX_SHARE`` of the scan's bounding
    box, its points along the room's outline (walls). Formats that cannot name a ceiling (``array:``,
    label 0) give such instances; none of the real dev scans or the generated preset datasets has one.
    """
    coord = np.asarray(coord, np.float64)
    instance = np.asarray(instance, np.int64)
    if coord.ndim != 2 or coord.shape[1] != 3 or len(coord) != len(instance):
        raise DataError(f"layout realism: expected (N, 3) points and (N,) instances, got {coord.shape} and "
                        f"{instance.shape}")
    out = RealismStats(scenes=1)
    finite = np.isfinite(coord).all(1)
    coord, instance = coord[finite], np.where(instance[finite] < 0, -1, instance[finite])
    if len(coord) < 10:
        return _one_scene(out)
    pts, inst = _voxel_points(coord, instance)
    floor = float(np.percentile(pts[:, 2], 2.0))
    h = pts[:, 2] - floor
    top = float(np.percentile(h, 99.5))
    box_area = float(np.prod(pts[:, :2].max(0) - pts[:, :2].min(0)))
    bg = inst < 0
    wall = bg & (h >= WALL_BAND[0]) & (h <= WALL_BAND[1])

    # floor-plan cells: every occupied cell of the scan, and those of each object
    cells = np.floor(pts[:, :2] / CELL).astype(np.int64)
    lo = cells.min(0)
    cells -= lo
    shape = cells.max(0) + 1
    flat = cells[:, 0] * shape[1] + cells[:, 1]
    plan = np.zeros((int(shape[0]) + 2, int(shape[1]) + 2), bool)  # padded by one empty cell
    plan[cells[:, 0] + 1, cells[:, 1] + 1] = True
    plan = ndimage.binary_fill_holes(ndimage.binary_closing(plan, iterations=2) | plan)
    edge = plan & ~ndimage.binary_erosion(plan)
    edge_xy = (np.argwhere(edge) - 1 + lo + 0.5) * CELL
    wall_tree = cKDTree(edge_xy) if len(edge_xy) >= 3 else None
    room_angle = _wall_directions(np.concatenate([edge_xy, pts[wall, :2]]))
    ids, counts = np.unique(inst[inst >= 0], return_counts=True)
    objects = ids[counts >= MIN_VOXELS]
    obj_cells = np.zeros(int(shape[0] * shape[1]), np.int32)  # number of objects covering each cell
    cell_sets = {}
    for o in objects:
        c = np.unique(flat[inst == o])
        cell_sets[int(o)] = c
        obj_cells[c] += 1
    all_cells = np.unique(flat)
    covered = np.unique(np.concatenate(list(cell_sets.values()))) if cell_sets else np.zeros(0, np.int64)
    out.values["coverage"].append(float(len(covered) / max(len(all_cells), 1)))

    obj_xy = {int(o): pts[inst == o, :2] for o in objects}
    trees = {o: cKDTree(xy) for o, xy in obj_xy.items()}
    order = list(obj_xy)
    lo_xy = np.array([obj_xy[o].min(0) for o in order]).reshape(-1, 2)
    hi_xy = np.array([obj_xy[o].max(0) for o in order]).reshape(-1, 2)
    ring = int(round(RING / CELL))
    di, dj = np.mgrid[-ring:ring + 1, -ring:ring + 1]
    disc = (di * di + dj * dj) <= ring * ring
    di, dj = di[disc], dj[disc]  # cell offsets within RING, computed once for every object
    for k, (o, xy) in enumerate(obj_xy.items()):
        out.objects += 1
        z = pts[inst == o, 2]
        low, high = float(z.min() - floor), float(z.max() - floor)
        out.values["height"].append(max(low, 0.0))
        if high >= top - STRUCTURE_GAP and (
                (low >= CEILING_LOW and len(cell_sets[o]) >= CEILING_SHARE * len(all_cells))
                or (low <= STRUCTURE_GAP and float(np.prod(hi_xy[k] - lo_xy[k])) >= WALLS_BOX_SHARE * box_area
                    and wall_tree is not None and float(np.median(wall_tree.query(xy, k=1)[0])) <= WALLS_HUG)):
            out.structure_suspects.append(int(o))
        if wall_tree is not None:
            out.values["wall_distance"].append(float(wall_tree.query(xy, k=1)[0].min()))
        c = xy - xy.mean(0)
        w, vec = np.linalg.eigh(c.T @ c / len(c))
        if room_angle is not None and w[1] > ELONGATION ** 2 * max(w[0], 1e-12):
            ang = np.degrees(np.arctan2(vec[1, 1], vec[0, 1])) % 90.0
            diff = abs(ang - room_angle) % 90.0
            out.values["misalignment"].append(float(min(diff, 90.0 - diff)))
        if len(order) > 1:  # nearest other object: visit them by box distance, stop when no box can be closer
            gap = np.linalg.norm(np.maximum(0.0, np.maximum(lo_xy - hi_xy[k], lo_xy[k] - hi_xy)), axis=1)
            gap[k] = np.inf
            best = np.inf
            for j in np.argsort(gap, kind="stable"):
                if gap[j] >= best:
                    break
                best = min(best, float(trees[order[j]].query(xy, k=1)[0].min()))
            out.values["neighbour"].append(best)
        # free space: cells within RING of the footprint (not in it) covered by another object
        mine = cell_sets[o]
        ci, cj = np.divmod(mine, shape[1])
        ii, jj = (ci[:, None] + di).ravel(), (cj[:, None] + dj).ravel()
        ok = (ii >= 0) & (jj >= 0) & (ii < shape[0]) & (jj < shape[1])
        idx = np.setdiff1d(ii[ok] * shape[1] + jj[ok], mine)
        if len(idx):
            taken = obj_cells[idx] > 0
            out.values["free_space"].append(float(1.0 - taken.mean()))
    if out.structure_suspects:
        log.warning("%s: instance(s) %s look like room structure (a ceiling, or walls from floor to ceiling) labelled "
                    "as objects; layout realism counts them as objects: set their instance id to 0, or read the scan "
                    "with a format that names ceilings (scannet: with its label map)", where,
                    ", ".join(str(i) for i in out.structure_suspects))
    return _one_scene(out)


def _one_scene(stats: RealismStats) -> RealismStats:
    """``stats`` of one scene with its value counts recorded as that scene's."""
    stats.per_scene = {k: [len(stats.values[k])] for k in STATS}
    return stats


# --------------------------------------------------------------------------------------------
# reference distributions and the score


@dataclass(frozen=True)
class RealismReference:
    """Quantiles of each statistic on reference scans."""

    quantiles: dict[str, np.ndarray]
    source: str
    scenes: int
    objects: int

    @classmethod
    def from_stats(cls, stats: RealismStats, source: str) -> "RealismReference":
        q = np.linspace(0, 1, QUANTILES)
        arrs = stats.arrays()
        missing = [k for k in STATS if len(arrs[k]) == 0]
        if missing:
            raise DataError(f"{source}: no values for {', '.join(missing)} (are there labelled objects?)")
        return cls({k: np.quantile(arrs[k], q) for k in STATS}, source, stats.scenes, stats.objects)

    def to_json(self) -> dict:
        return {"version": REFERENCE_VERSION, "source": self.source, "scenes": self.scenes, "objects": self.objects,
                "quantiles": {k: [round(float(x), 5) for x in v] for k, v in self.quantiles.items()}}

    @classmethod
    def from_json(cls, d: dict, where: str) -> "RealismReference":
        try:
            if d.get("version") != REFERENCE_VERSION:
                raise ValueError(f"version {d.get('version')!r}, expected {REFERENCE_VERSION}")
            q = {k: np.asarray(d["quantiles"][k], np.float64) for k in STATS}
            if any(len(v) != QUANTILES or not np.all(np.diff(v) >= 0) for v in q.values()):
                raise ValueError(f"each statistic needs {QUANTILES} non-decreasing quantiles")
            return cls(q, str(d.get("source", where)), int(d.get("scenes", 0)), int(d.get("objects", 0)))
        except (KeyError, TypeError, ValueError) as e:
            raise DataError(f"{where}: not a layout realism reference ({e})") from None

    @classmethod
    def load(cls, path: str | Path | None = None) -> "RealismReference":
        """The reference in ``path``, or the shipped one (real ScanNet scans)."""
        if path is None:
            text = resources.files("assist3d").joinpath("resources", "realism", "scannet-dev.json").read_text(encoding="utf-8")
            return cls.from_json(reading.parse_json(text, "assist3d/resources/realism/scannet-dev.json"),
                                 "assist3d/resources/realism/scannet-dev.json")
        p = Path(path)
        try:
            data = reading.read_json(p, what="layout realism reference")
        except DataError as e:
            raise DataError(f"{shown(p, 400)}: unreadable layout realism reference ({reading.problem(e, p)})") from None
        return cls.from_json(data, str(p))


def _ks_to_quantiles(values: np.ndarray, ref_q: np.ndarray) -> float:
    """Kolmogorov-Smirnov distance between ``values`` and the distribution given by its quantiles
    ``ref_q`` (piecewise-linear CDF between quantiles; atoms where quantiles repeat)."""
    values = np.sort(values)
    grid = np.unique(np.concatenate([values, ref_q]))
    probs = np.linspace(0, 1, len(ref_q))
    # reference CDF at x: the largest probability whose quantile is <= x (right-continuous, atoms kept)
    idx = np.searchsorted(ref_q, grid, side="right")
    below = np.where(idx > 0, probs[np.clip(idx - 1, 0, len(probs) - 1)], 0.0)
    # linear interpolation inside a gap between two distinct quantiles
    nxt = np.clip(idx, 0, len(ref_q) - 1)
    prv = np.clip(idx - 1, 0, len(ref_q) - 1)
    gap = (idx > 0) & (idx < len(ref_q)) & (ref_q[nxt] > ref_q[prv])
    frac = np.where(gap, (grid - ref_q[prv]) / np.where(gap, ref_q[nxt] - ref_q[prv], 1.0), 0.0)
    ref_cdf = np.where(gap, probs[prv] + frac * (probs[nxt] - probs[prv]), below)
    emp = np.searchsorted(values, grid, side="right") / len(values)
    emp_left = np.searchsorted(values, grid, side="left") / len(values)
    return float(max(np.abs(emp - ref_cdf).max(), np.abs(emp_left - ref_cdf).max()))


def realism_score(stats: RealismStats, reference: RealismReference) -> tuple[float | None, dict, str | None]:
    """``(layout_realism 0-100 or None, {statistic: KS distance}, reason when None)``."""
    arrs = stats.arrays()
    missing = [k for k in STATS if len(arrs[k]) == 0]
    if stats.objects == 0:
        return None, {}, "no labelled object with enough points"
    if missing:
        return None, {}, f"no values for {', '.join(missing)}"
    ks = {k: round(_ks_to_quantiles(arrs[k], reference.quantiles[k]), 4) for k in STATS}
    return round(100.0 * (1.0 - float(np.mean(list(ks.values())))), 2), ks, None


def realism_profile(stats: RealismStats, reference: RealismReference) -> dict | None:
    """Which way a dataset differs from the reference, in the statistics' own units:
    ``{"objects_per_scene": {"dataset": mean, "reference": mean}, STAT: {"dataset": median, "reference":
    median}, ...}`` for the six statistics (metres, degrees, shares). The score's KS distances say how far
    each distribution is from the reference's; this says, for instance, that a dataset's rooms cover less
    floor or hold fewer objects than real ones. None when the score cannot be computed; a reference read
    from a JSON file without its scene count gives ``objects_per_scene`` a null reference side.
    """
    arrs = stats.arrays()
    if stats.objects == 0 or stats.scenes == 0 or any(len(arrs[k]) == 0 for k in STATS):
        return None
    half = (QUANTILES - 1) // 2  # quantiles are at linspace(0, 1, QUANTILES): the middle one is the median
    ref_per_scene = round(reference.objects / reference.scenes, 2) if reference.scenes else None
    out = {"objects_per_scene": {"dataset": round(stats.objects / stats.scenes, 2), "reference": ref_per_scene}}
    for k in STATS:
        out[k] = {"dataset": round(float(np.median(arrs[k])), 4),
                  "reference": round(float(reference.quantiles[k][half]), 4)}
    return out


def realism_standard_error(stats: RealismStats, reference: RealismReference, rng: np.random.Generator,
                           draws: int = BOOTSTRAP_DRAWS) -> tuple[float | None, str | None]:
    """``(standard error of layout_realism, reason when None)``: the standard deviation of the score
    over ``draws`` resamplings of the dataset's scenes with replacement (each scene's values go
    together, the reference is held fixed). It says how much the score would move with other scenes
    from the same generator; it does not cover the reference's own sampling (10 real scans for the
    shipped one). None for fewer than 2 scenes or a sample without scene structure.
    """
    if stats.scenes < 2:
        return None, "fewer than 2 scenes"
    if not stats.has_scenes():
        return None, "values not attributed to scenes"
    arrs = stats.arrays()
    counts = {k: np.asarray(stats.per_scene[k], np.int64) for k in STATS}
    starts = {k: np.r_[0, np.cumsum(counts[k])[:-1]] for k in STATS}
    scores = []
    for _ in range(draws):
        pick = rng.integers(0, stats.scenes, stats.scenes)
        ks = []
        for k in STATS:
            n, first = counts[k][pick], starts[k][pick]
            if n.sum() == 0:  # no value of this statistic in the resample: the score is undefined there
                break
            # the picked scenes' value ranges, concatenated: offset of each value within its scene + its start
            idx = np.arange(n.sum()) + np.repeat(first - np.r_[0, np.cumsum(n)[:-1]], n)
            ks.append(_ks_to_quantiles(arrs[k][idx], reference.quantiles[k]))
        else:
            scores.append(100.0 * (1.0 - float(np.mean(ks))))
    if len(scores) < draws // 2:
        return None, "too few scenes with every statistic"
    return round(float(np.std(scores, ddof=1)), 2), None


def matched_sample(stats: RealismStats, like: RealismStats, rng: np.random.Generator) -> RealismStats:
    """A random subsample of ``stats`` with as many values per statistic as ``like`` has.

    The KS distance of a sample from a distribution grows as the sample shrinks (about
    ``0.87 / sqrt(n)`` for a sample of the distribution itself), so a held-out real room of a dozen
    objects and a generated dataset of thousands are not scored on the same footing. Scoring
    ``matched_sample(generated, room, rng)`` against the room's reference puts them there. Values are
    drawn without replacement, per statistic (scene statistics from the scene values, object
    statistics from the pooled object values).
    """
    src, out = stats.arrays(), RealismStats()
    for k in STATS:
        n = len(like.values[k])
        if n > len(src[k]):
            raise DataError(f"matched sample: {n} values of {k} wanted, {len(src[k])} available")
        out.values[k] = src[k][rng.choice(len(src[k]), size=n, replace=False)].tolist()
    out.scenes, out.objects = like.scenes, like.objects
    return out


def realism_spec(spec: str) -> str:
    """``spec`` as this score reads it: with ``objects=annotated`` added when its format takes the
    ``objects`` option (the ScanNet-protocol readers) and the spec does not set it, so that a real
    scan counts every annotated object, as a generated one does."""
    fmt, _, options = parse_spec(spec)
    if "objects" in READERS.get(fmt).options and "objects" not in options:
        return f"{spec}{'&' if '?' in spec else '?'}objects=annotated"
    return spec


def stats_of_dataset(spec: str, max_scenes: int | None = None) -> RealismStats:
    """Pooled statistics of the first ``max_scenes`` scenes of a labelled dataset ``FORMAT:PATH``
    (read through :func:`realism_spec`)."""
    ds = open_dataset(realism_spec(spec))
    total = RealismStats()
    for sid in list(ds.scene_ids)[: max_scenes or None]:
        s = ds.load(sid)
        total.add(scene_stats(s.coord, s.instance, f"{spec} scene {sid}"))
    return total


def load_reference(spec: str | None, max_scenes: int | None = None) -> RealismReference:
    """The reference named on the command line: None = the shipped one, a ``.json`` file, or a
    labelled dataset ``FORMAT:PATH`` whose statistics are measured now."""
    if spec is None:
        return RealismReference.load()
    if spec.endswith(".json") and ":" not in spec.split("/", 1)[0]:
        return RealismReference.load(spec)
    return RealismReference.from_stats(stats_of_dataset(spec, max_scenes), realism_spec(spec))  # names the reading
