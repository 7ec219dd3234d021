"""Compare datasets on the paper's three principles: geometry diversity, context complexity and
layout reasonability, on any dataset a reader understands (synthetic or real)."""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np

from ...assets import open_catalog
from ...assets.catalog import Catalog
from ...core.contracts import SceneLayout
from ...data import open_dataset
from ...core import reading
from ...core.errors import AssistError, DataError, shown
from ...export.manifest import read_manifest
from ...core.fileio import atomic_path
from .vlm import vlm_layout_score
from ...core.rng import make_rng
from .context import context_complexity, per_class_max_cooccurrence
from .diversity import Codebook, code_entropy, fit_codebook, geometry_diversity, geometry_diversity_se
from .features import FEATURE_DIM, instance_descriptors
from .plausibility import score_layout
from .realism import (RealismReference, RealismStats, realism_profile, realism_score, realism_spec,
                      realism_standard_error, scene_stats)

log = logging.getLogger(__name__)

POOL_PER_DATASET = 4000
CODEBOOK_DRAWS = 8  # codebooks behind geometry_diversity_sd (draw 0 gives the value)


@dataclass
class DatasetSummary:
    """Everything the metrics need from one dataset, gathered in one pass over its scenes."""

    name: str  # the dataset as the user named it (the key of the metrics table)
    spec: str = ""  # FORMAT:PATH (a bare folder gets "assist3d:")
    scenes: int = 0
    instances: int = 0
    features: np.ndarray = field(default_factory=lambda: np.zeros((0, FEATURE_DIM), np.float32))
    feature_counts: list = field(default_factory=list)  # descriptors per scene, in the order of ``features``
    scene_classes: list = field(default_factory=list)
    layout_scores: list = field(default_factory=list)
    layout_components: list = field(default_factory=list)
    layout_reason: str | None = None
    vlm_scores: list = field(default_factory=list)
    realism: RealismStats = field(default_factory=RealismStats)


def normalise_spec(spec: str) -> str:
    """A bare folder means our own format (``assist3d:``)."""
    head = spec.split(":", 1)[0]
    if ":" in spec and head in {"scannet", "scannetpp", "s3dis", "pointcept", "assist3d", "array"}:
        return spec
    return f"assist3d:{spec}"


def _dataset_catalog(root: Path, assets: str | None) -> Catalog | None:
    """The catalog a generated dataset was made from: --assets, else the one its manifest names."""
    if assets:
        return Catalog.open(assets)
    m = read_manifest(root)
    if m is None:
        return None
    path = m.get("catalog") or m.get("assets")  # `assist3d generate` writes the catalog folder as "assets"
    if isinstance(path, dict):
        path = path.get("path")
    if path and Catalog.exists(path):
        return Catalog.open(path)
    acfg = (m.get("config") or {}).get("assets") or {}
    if acfg.get("library") and Catalog.exists(acfg["library"]):
        return Catalog.open(acfg["library"])
    try:
        return open_catalog(None, procedural_count=int(acfg.get("procedural_count", 2000)),
                            procedural_seed=int(acfg.get("procedural_seed", 0)))
    except AssistError as e:
        log.warning("%s: cannot open the catalog it was generated from (%s)", root, e)
        return None


def summarize_dataset(spec: str, *, assets: str | None = None, max_scenes: int | None = None,
                      seed: int = 0, vlm_cfg=None) -> DatasetSummary:
    """Read a dataset once (a real dataset whose reader keeps the benchmark's classes twice, the
    second time with every annotated object for layout realism): instance descriptors, per-scene
    class sets, layout scores."""
    given, spec = spec, normalise_spec(spec)
    ds = open_dataset(spec)
    # layout realism counts every annotated object of a real scan (as of a generated one): a second
    # reading where the reader keeps only the benchmark's classes by default
    counted_as = realism_spec(spec)
    realism_ds = open_dataset(counted_as) if counted_as != spec else None
    summary = DatasetSummary(name=given, spec=spec)
    fmt = spec.split(":", 1)[0]
    catalog = None
    if fmt == "assist3d":
        catalog = _dataset_catalog(Path(ds.root), assets)
        if catalog is None:
            summary.layout_reason = "the asset catalog of this dataset was not found (pass --assets)"
    else:
        summary.layout_reason = f"{fmt} datasets have no layout JSON"
    ids = list(ds.scene_ids)[: max_scenes or None]
    feats = []
    for sid in ids:
        sample = ds.load(sid)
        # one stream per scene, keyed by the scene's id and never by the dataset's path: the same
        # scenes give the same descriptors wherever the dataset lies and whichever others are read
        inst_ids, f = instance_descriptors(sample.coord, sample.instance, rng=make_rng(seed, "metrics", str(sid)))
        feats.append(f)
        summary.feature_counts.append(len(f))
        counted = sample if realism_ds is None else realism_ds.load(sid)
        summary.realism.add(scene_stats(counted.coord, counted.instance, f"{spec} scene {sid}"))
        layout = _load_layout(Path(ds.root) / sid) if fmt == "assist3d" else None
        if layout is not None:
            summary.scene_classes.append({i.class_name for i in layout.instances})
            summary.instances += len(layout.instances)
            if catalog is not None:
                try:
                    rep = score_layout(layout, catalog)
                    summary.layout_scores.append(rep.score)
                    summary.layout_components.append(rep.components)
                except AssistError as e:
                    summary.layout_reason = str(e)
                    catalog = None
                    summary.layout_scores = []
            if vlm_cfg is not None:
                s = vlm_layout_score(Path(ds.root) / sid, vlm_cfg)
                if s is not None:
                    summary.vlm_scores.append(s)
        else:
            # classes from point labels: each instance's majority semantic label
            m = sample.instance >= 0
            inst = sample.instance[m]
            seg = sample.segment[m]
            classes = set()
            for u in np.unique(inst):
                labs = seg[inst == u]
                labs = labs[labs >= 0]
                classes.add(f"class_{int(np.bincount(labs).argmax())}" if len(labs) else f"instance_{int(u)}")
            summary.scene_classes.append(classes)
            summary.instances += int(len(np.unique(inst)))
        summary.scenes += 1
    summary.features = np.concatenate(feats) if feats else np.zeros((0, FEATURE_DIM), np.float32)
    if fmt == "assist3d" and catalog is not None and not summary.layout_scores and summary.scenes:
        summary.layout_reason = "no layout.json in the scene folders"
    return summary


def _load_layout(scene_dir: Path) -> SceneLayout | None:
    p = scene_dir / "layout.json"
    if not p.is_file():
        return None
    try:
        return SceneLayout.from_json(reading.read_json(p, what="layout"))
    except DataError as e:
        raise DataError(f"{shown(p, 400)}: unreadable layout ({reading.problem(e, p)})") from None
    except (KeyError, ValueError, TypeError, AttributeError, IndexError) as e:
        raise DataError(f"{shown(p, 400)}: unreadable layout ({type(e).__name__}: {shown(e)})") from None


def shared_codebook(summaries: Sequence[DatasetSummary], *, seed: int = 0, k: int = 64, draw: int = 0) -> Codebook:
    """A codebook fitted on an equal-sized random pool from each dataset.

    Every dataset's pool is drawn from the same seeded stream and the pooled descriptors are put in
    one canonical order before the fit, so the codebook depends on which datasets are compared and
    on ``seed``, never on the order they are listed in or on where they lie. ``draw`` > 0 gives
    another pool and fit from the same seed (:func:`codebook_draws`); draw 0 is the codebook."""
    keys = () if draw == 0 else (int(draw),)
    pools = []
    n = min([len(s.features) for s in summaries if len(s.features)] or [0])
    n = min(n, POOL_PER_DATASET)
    for s in summaries:
        if len(s.features) == 0:
            continue
        pick = make_rng(seed, "codebook-pool", *keys).choice(len(s.features), size=n, replace=False) \
            if len(s.features) > n else np.arange(len(s.features))
        pools.append(s.features[pick])
    if not pools:
        raise DataError("no instance with enough points in any dataset: cannot fit a shape codebook")
    pool = np.concatenate(pools)
    pool = pool[np.lexsort(pool.T[::-1])]  # rows sorted on the first column, then the second, ...
    return fit_codebook(pool, k=k, rng=make_rng(seed, "codebook", *keys))


def codebook_draws(summaries: Sequence[DatasetSummary], *, seed: int = 0, k: int = 64,
                   draws: int = CODEBOOK_DRAWS) -> list[Codebook]:
    """Draws 1 .. ``draws - 1`` of :func:`shared_codebook`: with draw 0 they give
    ``geometry_diversity_sd``, how far a dataset's value moves with the codebook's pool and fit."""
    return [shared_codebook(summaries, seed=seed, k=k, draw=d) for d in range(1, draws)]


def _geometry_se(summary: DatasetSummary, codes: np.ndarray, k: int, seed: int) -> tuple[float | None, str | None]:
    """``geometry_diversity_se`` of one dataset from its descriptors' ``codes`` under a ``k``-code codebook
    (its scenes resampled, seeded by ``seed``)."""
    if sum(summary.feature_counts) != len(codes):
        return None, "descriptors not attributed to scenes"
    per_scene = np.split(codes, np.cumsum(summary.feature_counts)[:-1])
    return geometry_diversity_se(per_scene, k, make_rng(seed, "geometry_diversity_se"))


def metrics_table(summaries: Sequence[DatasetSummary], codebook: Codebook,
                  reference: RealismReference | None = None, seed: int = 0,
                  other_codebooks: Sequence[Codebook] = ()) -> dict:
    """``{name: {"geometry_diversity", "context_complexity", "layout_score", "layout_realism", "scenes",
    "instances", ...}}`` keyed by each dataset as the user named it (``"dataset"`` holds its
    ``FORMAT:PATH`` form); a metric that cannot be computed is None, with the reason under
    ``"notes"``. ``other_codebooks`` (:func:`codebook_draws`) give ``geometry_diversity_sd``, the
    standard deviation of the value over them and ``codebook``; without them it is None.
    ``layout_realism_profile`` (:func:`~.realism.realism_profile`) gives objects a scene and each realism
    statistic's median beside the reference's, so a reader sees which way a dataset differs.
    ``reference`` defaults to the shipped real-scan statistics; ``seed`` seeds the scene
    resamplings behind ``layout_realism_se`` and ``geometry_diversity_se`` (one stream each, the same
    for every dataset)."""
    reference = reference if reference is not None else RealismReference.load()
    out = {}
    for s in summaries:
        notes = {}
        realism, realism_parts, why = realism_score(s.realism, reference)
        realism_se = None
        if realism is None:
            notes["layout_realism"] = why
        else:
            realism_se, why_se = realism_standard_error(s.realism, reference, make_rng(seed, "layout_realism_se"))
            if realism_se is None:
                notes["layout_realism_se"] = why_se
        codes = codebook.assign(s.features) if len(s.features) else None  # coded once: the value and its se
        gd = code_entropy(codes, len(codebook.centers)) if codes is not None else None
        gd_sd = gd_se = None
        if gd is None:
            notes["geometry_diversity"] = "no instance with enough points"
        else:
            if other_codebooks:
                values = [gd] + [geometry_diversity(s.features, book) for book in other_codebooks]
                gd_sd = float(np.std(values, ddof=1))
            else:
                notes["geometry_diversity_sd"] = "one codebook only (e.g. a codebook file was given)"
            gd_se, why_se = _geometry_se(s, codes, len(codebook.centers), seed)
            if gd_se is None:
                notes["geometry_diversity_se"] = why_se
        cc = context_complexity(s.scene_classes) if s.scene_classes else None
        if cc is None:
            notes["context_complexity"] = "no scenes"
        ls = float(np.mean(s.layout_scores)) if s.layout_scores else None
        if ls is None:
            notes["layout_score"] = s.layout_reason or "no layouts"
            log.info("%s: layout score not computed: %s", s.name, notes["layout_score"])
        comps = None
        if s.layout_components:
            comps = {k: round(float(np.mean([c[k] for c in s.layout_components])), 4) for k in s.layout_components[0]}
        row = {
            "geometry_diversity": None if gd is None else round(gd, 4),
            "geometry_diversity_sd": None if gd_sd is None else round(gd_sd, 4),
            "geometry_diversity_se": None if gd_se is None else round(gd_se, 4),
            "context_complexity": None if cc is None else round(cc, 4),
            "layout_score": None if ls is None else round(ls, 2),
            "scenes": s.scenes,
            "instances": s.instances,
            "layout_components": comps,
            "vlm_layout_score": round(float(np.mean(s.vlm_scores)), 2) if s.vlm_scores else None,
            "layout_realism": realism,
            "layout_realism_se": realism_se,
            "layout_realism_components": realism_parts or None,
            "layout_realism_profile": realism_profile(s.realism, reference),  # None wherever the score is
            "layout_realism_reference": reference.source,
            "codes": len(codebook.centers),
            "dataset": s.spec or s.name,
        }
        if notes:
            row["notes"] = notes
        out[s.name] = row
    return out


REALISM_UNITS = {"wall_distance": " m", "misalignment": " deg", "height": " m", "neighbour": " m", "free_space": "",
                 "coverage": ""}


def realism_hint(row: dict, most: int = 2) -> str:
    """One line on where a dataset's arrangements differ most from the reference's: the ``most`` statistics
    with the largest KS distance, each with the dataset's and the reference's medians, and objects a scene."""
    parts, prof = row["layout_realism_components"], row["layout_realism_profile"]
    worst = sorted(parts, key=lambda k: (-parts[k], k))[:most]
    said = [f"{k} (KS {parts[k]:.2f}; median {prof[k]['dataset']:.2f}{REALISM_UNITS[k]} against "
            f"{prof[k]['reference']:.2f}{REALISM_UNITS[k]})" for k in worst]
    ops = prof["objects_per_scene"]
    line = f"layout realism furthest from the reference on {' and '.join(said)}; {ops['dataset']:.1f} objects a scene"
    return line + (f" against {ops['reference']:.1f}" if ops["reference"] is not None else "")


def short_labels(names: Sequence[str]) -> list[str]:
    """Legend labels: each dataset's last path component when those are unique (the folders of one
    comparison), else the names as given."""
    tails = [Path(n.split(":", 1)[-1]).name or n for n in names]
    return tails if len(set(tails)) == len(tails) else list(names)


def plot_summaries(summaries: Sequence[DatasetSummary], codebook: Codebook, path: str | Path) -> None:
    """A PNG: shape-code histograms, per-class max co-occurrence, per-scene layout scores."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(16, 4.6))
    k = len(codebook.centers)
    for s, label in zip(summaries, short_labels([s.name for s in summaries])):
        if len(s.features):
            p = np.bincount(codebook.assign(s.features), minlength=k) / len(s.features)
            axes[0].plot(np.sort(p)[::-1], label=label, lw=1.6)
        if s.scene_classes:
            vals = sorted(v for _, v in per_class_max_cooccurrence(s.scene_classes).values())
            axes[1].plot(np.linspace(0, 1, len(vals)), vals, label=label, lw=1.6)
        if s.layout_scores:
            axes[2].hist(s.layout_scores, bins=20, range=(0, 100), alpha=0.5, label=label)
    axes[0].set(title="Geometry: shape-code shares (sorted)", xlabel="code rank", ylabel="share of instances")
    axes[1].set(title="Context: max co-occurrence per class", xlabel="class quantile", ylabel="max P(other | class)")
    axes[2].set(title="Layout: plausibility per scene", xlabel="score (0-100)", ylabel="scenes")
    for a in axes:
        a.grid(alpha=0.3)
        if a.has_data():
            a.legend(fontsize=8)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
