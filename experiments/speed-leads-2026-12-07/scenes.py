"""Shared by the scripts here: the first N scenes of `assist3d generate --seed 0` (paper settings, default
config and catalog) as the renderer sees them, (scene mesh, room, render config) each, captured in-process."""
from __future__ import annotations

import tempfile

import assist3d.pipeline.scene as ps
import assist3d.render as R
from assist3d.config import parse_config
from assist3d.pipeline.scene import SceneGenerator, SceneJob


def rendered_scenes(n: int, rays: str = "adaptive") -> list:
    got = []
    orig = R.render_point_cloud

    def grab(scene, room, cfg, **kw):
        got.append((scene, room, cfg))
        return orig(scene, room, cfg, **kw)

    names = [k for k in dir(ps) if getattr(ps, k) is orig]
    for k in names:
        setattr(ps, k, grab)
    try:
        gen = SceneGenerator(parse_config({"seed": 0, "render": {"rays": rays}}))
        with tempfile.TemporaryDirectory() as tmp:
            for i in range(n):
                gen.scene(SceneJob(i, tmp))
    finally:
        for k in names:
            setattr(ps, k, orig)
    return got
