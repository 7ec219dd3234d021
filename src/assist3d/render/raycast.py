"""Ray casting backends behind one interface.

* ``embree`` (default): Intel Embree through the self-contained ``embreex`` wheel. One BVH per
  scene; ``EmbreeScene.run`` releases the GIL, so views are cast from several Python threads.
* ``numpy``: an exact, dependency-free reference (vectorised Moller-Trumbore in float64 over
  all triangles, in bounded chunks). Slow; meant for tests and tiny scenes.

Both return, per ray, the ray parameter ``t`` of the nearest hit (``inf`` for a miss) and the
hit triangle's index (``-1`` for a miss). Rays are given as float32 origins and (not necessarily
unit) directions; a hit point is ``origin + t * direction``.
"""

from __future__ import annotations

import logging
from typing import Callable, Protocol

import numpy as np

from ..core.errors import RenderError
from ..core.registry import Registry

log = logging.getLogger(__name__)

__all__ = ["RayCaster", "EmbreeCaster", "NumpyCaster", "make_caster", "CASTERS", "BACKENDS"]

BACKENDS = ("embree", "numpy")  # the built-in casters (CASTERS below may hold more)


class RayCaster(Protocol):
    """Nearest-hit queries against one triangle set."""

    def cast(self, origins: np.ndarray, directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """origins, directions (N, 3) float32 -> t (N,) float32 (inf = miss), face (N,) int32."""
        ...


def _check_rays(origins: np.ndarray, directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    o = np.ascontiguousarray(origins, dtype=np.float32)
    d = np.ascontiguousarray(directions, dtype=np.float32)
    if o.ndim != 2 or o.shape[1] != 3 or d.shape != o.shape:
        raise RenderError(f"rays: origins {o.shape} and directions {d.shape} must both be (N, 3)")
    return o, d


class EmbreeCaster:
    """Embree BVH over ``vertices`` (V, 3) float32 and ``faces`` (F, 3) int32."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray) -> None:
        try:
            from embreex import rtcore_scene
            from embreex.mesh_construction import TriangleMesh
        except ImportError as e:  # pragma: no cover - embreex is a core dependency
            raise RenderError(f"render.backend=embree needs the embreex package ({e}); "
                              "pip install embreex, or use render.backend=numpy") from None
        if len(faces) == 0:
            raise RenderError("scene has no triangles to ray-cast")
        self._scene = rtcore_scene.EmbreeScene()
        self._mesh = TriangleMesh(self._scene, np.ascontiguousarray(vertices, dtype=np.float32),
                                  np.ascontiguousarray(faces, dtype=np.int32))

    #: rays per Embree call: embreex returns nine values a ray (barycentrics, normal, ids), so a whole
    #: view at once would hold ~11 MB of them per view in flight
    chunk = 1 << 16

    def cast(self, origins: np.ndarray, directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        o, d = _check_rays(origins, directions)
        n = len(o)
        t = np.empty(n, np.float32)
        face = np.empty(n, np.int32)
        for a in range(0, n, self.chunk):
            res = self._scene.run(o[a:a + self.chunk], d[a:a + self.chunk], output=1)
            face[a:a + self.chunk] = res["primID"]
            t[a:a + self.chunk] = res["tfar"]
        t[face < 0] = np.inf
        return t, face


class NumpyCaster:
    """Brute-force Moller-Trumbore in float64; memory bounded by ``pairs_per_chunk`` ray-triangle
    pairs at a time. Ties (a ray through a shared edge) go to the lower triangle index."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, *, pairs_per_chunk: int = 2_000_000,
                 max_pairs: int = 5_000_000_000) -> None:
        if len(faces) == 0:
            raise RenderError("scene has no triangles to ray-cast")
        tri = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)]
        self._v0 = tri[:, 0]
        self._e1 = tri[:, 1] - tri[:, 0]
        self._e2 = tri[:, 2] - tri[:, 0]
        self._chunk = max(1, pairs_per_chunk // len(faces))
        self._max_pairs = max_pairs

    def cast(self, origins: np.ndarray, directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        o32, d32 = _check_rays(origins, directions)
        n, nf = len(o32), len(self._v0)
        if n * nf > self._max_pairs:
            raise RenderError(f"numpy backend: {n} rays x {nf} triangles exceeds its budget of {self._max_pairs} "
                              "ray-triangle tests; use render.backend=embree")
        t_out = np.full(n, np.inf, dtype=np.float64)
        f_out = np.full(n, -1, dtype=np.int32)
        e1, e2, v0 = self._e1, self._e2, self._v0
        for s in range(0, n, self._chunk):
            o = o32[s:s + self._chunk].astype(np.float64)[:, None, :]
            d = d32[s:s + self._chunk].astype(np.float64)[:, None, :]
            p = np.cross(d, e2[None])  # (r, f, 3)
            det = np.einsum("ij,rij->ri", e1, p)
            ok = np.abs(det) > 1e-12
            inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
            tv = o - v0[None]
            u = np.einsum("rij,rij->ri", tv, p) * inv
            q = np.cross(tv, e1[None])
            v = np.einsum("rij,rij->ri", d, q) * inv
            t = np.einsum("ij,rij->ri", e2, q) * inv
            hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
            t = np.where(hit, t, np.inf)
            best = np.argmin(t, axis=1)  # first (lowest index) among equal minima
            tb = t[np.arange(len(t)), best]
            got = np.isfinite(tb)
            t_out[s:s + len(t)] = tb
            f_out[s:s + len(t)] = np.where(got, best, -1)
        return t_out.astype(np.float32), f_out


#: ray casters by name: a factory ``(vertices, faces) -> RayCaster`` (``render.backend`` picks one)
CASTERS: Registry[Callable[[np.ndarray, np.ndarray], RayCaster]] = Registry("render backend", error=RenderError)
CASTERS.add("embree", EmbreeCaster)
CASTERS.add("numpy", NumpyCaster)


def make_caster(backend: str, vertices: np.ndarray, faces: np.ndarray) -> RayCaster:
    """The ray caster registered as ``backend`` in :data:`CASTERS` over a triangle set."""
    return CASTERS.get(backend)(vertices, faces)
