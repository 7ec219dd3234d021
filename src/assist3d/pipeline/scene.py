"""One scene end to end: select -> layout -> assemble -> render -> fuse -> write.

Scene ``k`` of a dataset with global seed ``S`` uses ``scene_seed(S, k)`` and ``scene_index=k``
everywhere, so it can be regenerated alone and equals the same scene of a full run.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..assets import class_list, open_catalog_for
from ..config import GenerateConfig
from ..export import write_scene
from ..export.glb import export_glb
from ..core.records import LLMUsage, SceneRecord, StageTimings
from ..core.errors import ConfigError
from ..planning.planners import PLANNERS, planner_name
from ..render import make_caster, render_point_cloud, verify_labels
from ..render.raycast import CASTERS
from ..core.rng import make_rng, scene_seed
from ..scene.assemble import assemble_scene
from ..scene.layout import build_layout

log = logging.getLogger(__name__)


def scene_name(index: int) -> str:
    """Folder name of scene ``index``: ``scene_000042``."""
    return f"scene_{index:06d}"


@dataclass(frozen=True)
class SceneJob:
    index: int
    out_dir: str
    verify: bool = False


def check_plugins(cfg: GenerateConfig) -> None:
    """Refuse, before any work, a relation planner or ray caster that no module registered: one line naming
    the key and the closest registered name. The config accepts any name, so a plugin registered from
    outside the package (``PLANNERS.add``, ``CASTERS.add``) is chosen like a built-in one."""
    for key, registry, name in (("layout.planner", PLANNERS, planner_name(cfg)),
                                ("render.backend", CASTERS, cfg.render.backend)):
        if name not in registry:
            raise ConfigError(f"{key}: unknown {registry.kind} {name!r}{registry.hint(name)}")


def scene_classes(catalog, cfg: GenerateConfig) -> tuple[str, ...]:
    """The class list a point's ``segment`` indexes: the catalog's classes, then ``door`` and ``window``
    when ``room.fill_openings`` is on and the catalog lacks them (appended, so the catalog's indices
    stay as they are)."""
    classes = class_list(catalog)
    if cfg.room.fill_openings:
        classes += tuple(k for k in ("door", "window") if k not in classes)
    return classes


class SceneGenerator:
    """Everything one process needs to generate scenes: the config and the opened catalog."""

    def __init__(self, cfg: GenerateConfig, *, threads: int | None = None) -> None:
        check_plugins(cfg)
        self.cfg = cfg
        if threads is not None:
            self.cfg = cfg.model_copy(update={"render": cfg.render.model_copy(update={"threads": threads})})
        self.catalog = open_catalog_for(cfg.assets)
        self.classes = scene_classes(self.catalog, cfg)

    @property
    def assets_label(self) -> str:
        return str(getattr(self.catalog, "root", "") or self.cfg.assets.library or "procedural")

    def scene(self, job: SceneJob) -> dict:
        """Generate and write scene ``job.index``; returns its completion marker."""
        cfg = self.cfg
        sid = scene_name(job.index)
        seed = scene_seed(cfg.seed, job.index)
        seconds = StageTimings()
        cpu0 = time.process_time()
        t0 = time.perf_counter()
        layout = build_layout(self.catalog, cfg, seed, scene_index=job.index)
        t_layout = time.perf_counter() - t0
        cpu = {"select+layout": time.process_time() - cpu0}
        seconds.select = float(layout.stats.timing.get("select", 0.0))  # planner, room, selection
        seconds.layout = round(t_layout - seconds.select, 4)
        if not layout.classes:
            layout = _with_classes(layout, self.classes)
        t0 = time.perf_counter()
        mesh = assemble_scene(layout, self.catalog, self.classes)
        seconds.assemble = round(time.perf_counter() - t0, 4)
        cpu["assemble"] = time.process_time() - cpu0 - cpu["select+layout"]
        caster = make_caster(cfg.render.backend, mesh.vertices, mesh.faces)
        t_bvh = time.perf_counter() - t0 - seconds.assemble
        res = render_point_cloud(mesh, layout.room, cfg.render, rng=make_rng(seed, "render"), scene_id=sid,
                                 caster=caster)
        seconds.render = round(res.timings["render"] + t_bvh, 4)
        seconds.fuse = res.timings["fuse"]
        cpu["render+fuse"] = time.process_time() - cpu0 - cpu["select+layout"] - cpu["assemble"]
        record = SceneRecord(
            id=sid, index=job.index, seed=seed, dataset_seed=cfg.seed,
            instances=len(layout.instances),
            instances_with_points=int(np.count_nonzero(np.unique(res.sample.instance) >= 0)),
            dropped=len(layout.dropped), planner=dict(layout.planner),
            vantage_points=[[round(float(v), 6) for v in c] for c in res.centers],
            render=res.stats, triangles=int(len(mesh.faces)),
            llm=LLMUsage.from_layout_stats(layout.stats), seconds=seconds,
            # CPU time of this process (all threads) per stage: a load-independent cost measure
            cpu_seconds={k: round(v, 4) for k, v in cpu.items()},
        )
        if job.verify:
            t0 = time.perf_counter()
            check = verify_labels(mesh, caster, res.sample, res.centers, pixel_counts=res.pixel_counts)
            record.check = {**check.to_json(), "ok": check.ok(), "seconds": round(time.perf_counter() - t0, 4)}
            if not check.ok():
                log.warning("%s: label check failed: %s", sid, record.check)
        glb = (lambda p: export_glb(layout, self.catalog, p)) if cfg.output.save_mesh else None
        # write_scene adds the file digests, the point count and seconds["write"] to the marker
        return write_scene(Path(job.out_dir) / sid, res.sample, layout, record.to_json(), ply=cfg.output.ply,
                           glb_writer=glb)


def _with_classes(layout, classes):
    return replace(layout, classes=tuple(classes))
