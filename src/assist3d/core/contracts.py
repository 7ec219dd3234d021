"""Typed contracts passed between pipeline stages.

Conventions used everywhere:

* Units are metres, angles radians unless a name says ``_deg``.
* World frame: z up, the floor at z = 0.
* An asset's canonical frame: z up, base at z = 0, footprint (bounding box in x and y) centred on
  the origin, width along x, depth along y, and the **front facing -y** (the back is at +y). A
  wall object hangs with its back (+y side) against the wall.
* Arrays at the boundaries are numpy arrays with fixed dtypes (given in each docstring); the
  dataclasses make them read-only so no stage can change another stage's data by accident.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field, fields
from typing import Any, Literal

import numpy as np

Group = Literal["floor", "wall", "obj"]
GROUPS: tuple[str, ...] = ("floor", "wall", "obj")


def _check_array(a: np.ndarray, name: str, ndim: int, last: int | None, dtype: Any) -> None:
    if not isinstance(a, np.ndarray):
        raise TypeError(f"{name}: expected a numpy array, got {type(a).__name__}")
    if a.ndim != ndim or (last is not None and a.shape[-1] != last):
        want = f"(n, {last})" if last is not None and ndim == 2 else f"{ndim}-d"
        raise ValueError(f"{name}: expected shape {want}, got {a.shape}")
    if a.dtype != np.dtype(dtype):
        raise ValueError(f"{name}: expected dtype {np.dtype(dtype)}, got {a.dtype}")


def _freeze(*arrays: np.ndarray) -> None:
    for a in arrays:
        a.flags.writeable = False


# --------------------------------------------------------------------------------------------
# Assets
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SupportSurface:
    """A horizontal surface of an asset that other objects can rest on.

    ``height`` is metres above the asset's base (canonical frame); ``polygon`` is the usable
    footprint in the canonical x-y plane, counter-clockwise, metres; ``clearance`` is the free
    height above it (e.g. up to the next shelf board), ``None`` when nothing is above.
    """

    height: float
    polygon: tuple[tuple[float, float], ...]
    clearance: float | None = None  # free height above the surface (shelves), None = unbounded

    def to_json(self) -> dict:
        d = {"height": round(float(self.height), 6), "polygon": [[round(x, 6), round(y, 6)] for x, y in self.polygon]}
        if self.clearance is not None:
            d["clearance"] = round(float(self.clearance), 6)
        return d

    @staticmethod
    def from_json(d: dict) -> "SupportSurface":
        c = d.get("clearance")
        return SupportSurface(float(d["height"]), tuple((float(x), float(y)) for x, y in d["polygon"]),
                              None if c is None else float(c))


@dataclass(frozen=True)
class AssetRecord:
    """One usable asset of a catalog. Its mesh lives in the catalog's cache (``mesh_file``)."""

    id: str  # stable id, e.g. "sh3d:BlendSwap-CC-0/chair_3" or "proc:chair_basic/000042"
    source: str  # "sh3d" | "meshes" | "procedural" | ...
    name: str  # human-readable name
    class_name: str  # normalised lower-case category used for sampling and metrics
    groups: tuple[str, ...]  # subset of GROUPS
    size: tuple[float, float, float]  # (width x, depth y, height z) metres, canonical frame
    supports: tuple[SupportSurface, ...] = ()
    triangles: int = 0
    mesh_file: str = ""  # path relative to the catalog folder
    license: str = ""
    attribution: str = ""
    family: str = ""  # procedural family, original catalog category, ...
    elevation: float = 0.0  # suggested height of the base above the floor (wall items), metres
    cluster: int | None = None  # shape-cluster id (metrics); None when not computed
    extra: dict = field(default_factory=dict)  # importer-specific facts (JSON-serialisable)

    def to_json(self) -> dict:
        return {
            "id": self.id,
            "source": self.source,
            "name": self.name,
            "class": self.class_name,
            "groups": list(self.groups),
            "size": [round(float(s), 6) for s in self.size],
            "supports": [s.to_json() for s in self.supports],
            "triangles": int(self.triangles),
            "mesh_file": self.mesh_file,
            "license": self.license,
            "attribution": self.attribution,
            "family": self.family,
            "elevation": round(float(self.elevation), 6),
            "cluster": self.cluster,
            "extra": self.extra,
        }

    @staticmethod
    def from_json(d: dict) -> "AssetRecord":
        return AssetRecord(
            id=d["id"],
            source=d["source"],
            name=d.get("name", d["id"]),
            class_name=d["class"],
            groups=tuple(d["groups"]),
            size=tuple(float(s) for s in d["size"]),  # type: ignore[arg-type]
            supports=tuple(SupportSurface.from_json(s) for s in d.get("supports", [])),
            triangles=int(d.get("triangles", 0)),
            mesh_file=d.get("mesh_file", ""),
            license=d.get("license", ""),
            attribution=d.get("attribution", ""),
            family=d.get("family", ""),
            elevation=float(d.get("elevation", 0.0)),
            cluster=d.get("cluster"),
            extra=dict(d.get("extra", {})),
        )


@dataclass(frozen=True)
class MeshData:
    """A triangle mesh with one colour per face.

    vertices: (V, 3) float32 metres; faces: (F, 3) int32; face_colors: (F, 3) uint8 RGB.
    """

    vertices: np.ndarray
    faces: np.ndarray
    face_colors: np.ndarray

    def __post_init__(self) -> None:
        _check_array(self.vertices, "vertices", 2, 3, np.float32)
        _check_array(self.faces, "faces", 2, 3, np.int32)
        _check_array(self.face_colors, "face_colors", 2, 3, np.uint8)
        if len(self.face_colors) != len(self.faces):
            raise ValueError(f"face_colors: {len(self.face_colors)} rows for {len(self.faces)} faces")
        _freeze(self.vertices, self.faces, self.face_colors)

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3) float32: min and max corner."""
        return np.stack([self.vertices.min(0), self.vertices.max(0)])


@dataclass(frozen=True)
class SkippedAsset:
    """An asset an importer could not use, with a one-line reason."""

    path: str
    reason: str

    def to_json(self) -> dict:
        return {"path": self.path, "reason": self.reason}


# --------------------------------------------------------------------------------------------
# Scenes
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Opening:
    """A door or window cut into wall ``wall`` (index of the polygon edge from vertex i to i+1).

    ``offset`` is the distance of the opening's centre from the wall's start vertex along the
    wall; ``bottom``/``top`` are heights above the floor. A *filled* opening (``instance`` set,
    ``room.fill_openings``) holds a labelled object, as real scans annotate doors and windows: a door
    frame and leaf (``leaf_deg`` open into the room, hinged at the wall-start side when ``hinge`` is 0,
    at the other side when 1) or a window frame; ``instance`` is its instance id.
    """

    kind: Literal["door", "window"]
    wall: int
    offset: float
    width: float
    bottom: float
    top: float
    instance: int | None = None
    leaf_deg: float = 0.0
    hinge: int = 0

    def to_json(self) -> dict:
        d = {"kind": self.kind, "wall": self.wall, "offset": round(self.offset, 6), "width": round(self.width, 6),
             "bottom": round(self.bottom, 6), "top": round(self.top, 6)}
        if self.instance is not None:  # only filled openings carry these keys (older files stay byte-identical)
            d.update(instance=int(self.instance), leaf_deg=round(self.leaf_deg, 6), hinge=int(self.hinge))
        return d

    @staticmethod
    def from_json(d: dict) -> "Opening":
        inst = d.get("instance")
        return Opening(d["kind"], int(d["wall"]), float(d["offset"]), float(d["width"]), float(d["bottom"]),
                       float(d["top"]), instance=None if inst is None else int(inst),
                       leaf_deg=float(d.get("leaf_deg", 0.0)), hinge=int(d.get("hinge", 0)))


@dataclass(frozen=True)
class Room:
    """A room shell: a simple floor polygon (counter-clockwise, metres) extruded to ``height``."""

    polygon: tuple[tuple[float, float], ...]
    height: float
    openings: tuple[Opening, ...] = ()
    ceiling: bool = True

    def to_json(self) -> dict:
        return {
            "polygon": [[round(x, 6), round(y, 6)] for x, y in self.polygon],
            "height": round(self.height, 6),
            "openings": [o.to_json() for o in self.openings],
            "ceiling": self.ceiling,
        }

    @staticmethod
    def from_json(d: dict) -> "Room":
        return Room(
            polygon=tuple((float(x), float(y)) for x, y in d["polygon"]),
            height=float(d["height"]),
            openings=tuple(Opening.from_json(o) for o in d.get("openings", [])),
            ceiling=bool(d.get("ceiling", True)),
        )


@dataclass(frozen=True)
class Relation:
    """A spatial relation of a planned object to an earlier object of its group.

    ``kind`` is one of :data:`assist3d.planning.relations.RELATIONS`; ``target`` is the index (in
    the planned order) of an earlier object, or ``None`` for global relations (edge, middle,
    height); ``value`` carries a number where the kind needs one (height range bounds in metres,
    a distance); ``hard`` relations filter candidate placements, soft ones only rank them.
    """

    kind: str
    target: int | None = None
    value: tuple[float, ...] = ()
    hard: bool = False

    def to_json(self) -> dict:
        d: dict[str, Any] = {"kind": self.kind, "target": self.target}
        if self.value:
            d["value"] = [round(float(v), 6) for v in self.value]
        if self.hard:
            d["hard"] = True
        return d

    @staticmethod
    def from_json(d: dict) -> "Relation":
        return Relation(d["kind"], d.get("target"), tuple(float(v) for v in d.get("value", ())), bool(d.get("hard", False)))


#: the group of the objects placed on one support: ``"on:<support instance id>"`` (floor and wall
#: groups are ``"floor"`` and ``"wall"``). Build and read it only with the three functions below.
ON_TOP_PREFIX = "on:"
GroupKind = Literal["floor", "wall", "obj"]


def on_top_group(support_id: int | None) -> str:
    """The group name of the objects placed on instance ``support_id``; None (a support that could not be
    placed) gives ``"on:None"``, the group its dropped objects carry in ``layout.json``."""
    return f"{ON_TOP_PREFIX}{None if support_id is None else int(support_id)}"


def on_top_support(group: str) -> int | None:
    """The support's instance id of an on-top group, None for any other group (or a malformed name)."""
    if not group.startswith(ON_TOP_PREFIX):
        return None
    tail = group[len(ON_TOP_PREFIX):]
    return int(tail) if tail.isdigit() else None


def group_kind(group: str) -> GroupKind:
    """``"floor"``, ``"wall"`` or ``"obj"`` (an on-top group, or ``"obj"`` itself) for a group name."""
    if group.startswith(ON_TOP_PREFIX) or group == "obj":
        return "obj"
    return group  # type: ignore[return-value]


@dataclass(frozen=True)
class PlacedInstance:
    """One object placed in a scene. ``pose`` maps the asset's canonical frame to the world.

    pose: (4, 4) float64, row-major, metres. ``parent`` is the id of the supporting instance for
    on-top objects, else ``None``. Instance ids start at 1 and are unique within a scene.
    """

    id: int
    asset: str
    class_name: str
    group: str
    pose: np.ndarray
    parent: int | None = None
    relations: tuple[Relation, ...] = ()

    def __post_init__(self) -> None:
        _check_array(self.pose, "pose", 2, 4, np.float64)
        _freeze(self.pose)

    def to_json(self) -> dict:
        return {
            "id": self.id,
            "asset": self.asset,
            "class": self.class_name,
            "group": self.group,
            "pose": [[round(float(v), 9) for v in row] for row in self.pose],
            "parent": self.parent,
            "relations": [r.to_json() for r in self.relations],
        }

    @staticmethod
    def from_json(d: dict) -> "PlacedInstance":
        return PlacedInstance(
            id=int(d["id"]),
            asset=d["asset"],
            class_name=d["class"],
            group=d["group"],
            pose=np.asarray(d["pose"], dtype=np.float64).reshape(4, 4).copy(),
            parent=d.get("parent"),
            relations=tuple(Relation.from_json(r) for r in d.get("relations", [])),
        )


@dataclass(frozen=True)
class DroppedObject:
    """A selected object the layout could not place, and why."""

    asset: str
    group: str
    reason: str

    def to_json(self) -> dict:
        return {"asset": self.asset, "group": self.group, "reason": self.reason}


@dataclass
class LayoutStats(Mapping[str, Any]):
    """What a layout run counted (``layout.json``'s ``stats``), typed; it still reads as the mapping it
    was (``stats["placed"]``, ``stats.get("timing")``), in the same key order.

    ``selected`` / ``placed``: objects per group kind (floor, wall, obj); ``dropped``: objects not placed;
    ``selection``: the selection stage's counters; ``llm_calls`` / ``cache_hits`` / ``repairs``: the
    relation planner's; ``placement``: the placement search's counters; ``notes``: what was dropped or
    fell back, and why (at most ``MAX_NOTES``); ``timing``: wall seconds per stage. Present only when
    they apply: ``llm_budget_groups`` (groups the rules planned because the LLM budget was spent),
    ``prompt_tokens`` and ``completion_tokens`` (endpoints that report them). Keys this version does
    not know, read from a newer file, are kept in ``extra`` and written back after the others."""

    selected: dict[str, int] = field(default_factory=dict)
    placed: dict[str, int] = field(default_factory=dict)
    dropped: int = 0
    selection: dict[str, Any] = field(default_factory=dict)
    llm_calls: int = 0
    cache_hits: int = 0
    repairs: int = 0
    placement: dict[str, float] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    timing: dict[str, float] = field(default_factory=dict)
    llm_budget_groups: int | None = None
    prompt_tokens: int | None = None
    completion_tokens: int | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    def _pairs(self) -> Iterator[tuple[str, Any]]:
        for f in fields(self):
            if f.name == "extra":
                continue
            v = getattr(self, f.name)
            if v is not None or f.default is not None:
                yield f.name, v
        yield from self.extra.items()

    def __getitem__(self, key: str) -> Any:
        for k, v in self._pairs():
            if k == key:
                return v
        raise KeyError(key)

    def __iter__(self) -> Iterator[str]:
        return (k for k, _ in self._pairs())

    def __len__(self) -> int:
        return sum(1 for _ in self._pairs())

    def to_json(self) -> dict[str, Any]:
        return dict(self._pairs())

    @staticmethod
    def from_json(d: Mapping[str, Any] | None) -> LayoutStats:
        d = dict(d or {})
        known = {f.name for f in fields(LayoutStats)} - {"extra"}
        return LayoutStats(**{k: v for k, v in d.items() if k in known},
                           extra={k: v for k, v in d.items() if k not in known})


@dataclass(frozen=True)
class SceneLayout:
    """A complete, serialisable scene layout (``layout.json``)."""

    room: Room
    instances: tuple[PlacedInstance, ...]
    dropped: tuple[DroppedObject, ...]
    seed: int
    seconds: float
    planner: dict = field(default_factory=dict)  # {group_name: "rules" | "llm:<model>"}
    stats: LayoutStats = field(default_factory=LayoutStats)
    classes: tuple[str, ...] = ()  # class list; instance class index = classes.index(class_name)

    def to_json(self) -> dict:
        return {
            "room": self.room.to_json(),
            "instances": [i.to_json() for i in self.instances],
            "dropped": [d.to_json() for d in self.dropped],
            "seed": self.seed,
            "seconds": round(self.seconds, 4),
            "planner": dict(self.planner),
            "stats": self.stats.to_json(),
            "classes": list(self.classes),
        }

    @staticmethod
    def from_json(d: dict) -> "SceneLayout":
        return SceneLayout(
            room=Room.from_json(d["room"]),
            instances=tuple(PlacedInstance.from_json(i) for i in d["instances"]),
            dropped=tuple(DroppedObject(x["asset"], x["group"], x["reason"]) for x in d.get("dropped", [])),
            seed=int(d.get("seed", 0)),
            seconds=float(d.get("seconds", 0.0)),
            planner=dict(d.get("planner", {})),
            stats=LayoutStats.from_json(d.get("stats")),
            classes=tuple(d.get("classes", [])),
        )


@dataclass(frozen=True)
class SceneMesh:
    """The assembled scene: one triangle soup with a per-face instance id.

    vertices (V, 3) float32 world metres; faces (F, 3) int32; face_colors (F, 3) uint8;
    face_instance (F,) int32, the instance id or -1 for background (floor, walls, ceiling);
    face_segment (F,) int32, the class index of the instance or -1 for background.
    ``background_names`` maps negative part codes in ``face_part`` to names ("floor", "wall_0",
    ...); face_part (F,) int32 is the instance id for objects and -(k+1) for background part k.
    """

    vertices: np.ndarray
    faces: np.ndarray
    face_colors: np.ndarray
    face_instance: np.ndarray
    face_segment: np.ndarray
    face_part: np.ndarray
    background_names: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        _check_array(self.vertices, "vertices", 2, 3, np.float32)
        _check_array(self.faces, "faces", 2, 3, np.int32)
        _check_array(self.face_colors, "face_colors", 2, 3, np.uint8)
        for name in ("face_instance", "face_segment", "face_part"):
            a = getattr(self, name)
            _check_array(a, name, 1, None, np.int32)
            if len(a) != len(self.faces):
                raise ValueError(f"{name}: {len(a)} entries for {len(self.faces)} faces")
        _freeze(self.vertices, self.faces, self.face_colors, self.face_instance, self.face_segment, self.face_part)


# --------------------------------------------------------------------------------------------
# Rendering and point clouds
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Camera:
    """A pinhole camera. ``pose`` maps camera to world (x right, y down, z forward: OpenCV).

    pose: (4, 4) float64.
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    pose: np.ndarray

    def __post_init__(self) -> None:
        _check_array(self.pose, "pose", 2, 4, np.float64)
        _freeze(self.pose)


@dataclass(frozen=True)
class RGBDView:
    """One rendered view. depth (H, W) float32 metres along the optical axis, 0 = no hit;
    color (H, W, 3) uint8; instance (H, W) int32 (-1 background or miss); face (H, W) int32 hit
    triangle index or -1."""

    camera: Camera
    depth: np.ndarray
    color: np.ndarray
    instance: np.ndarray
    face: np.ndarray


@dataclass(frozen=True)
class PointSample:
    """A labelled point cloud, the unit every reader returns and every writer takes.

    coord (N, 3) float32 metres; color (N, 3) uint8; normal (N, 3) float32 (zeros if unknown);
    instance (N,) int32, -1 = no object (background or void); segment (N,) int32 class index,
    -1 = background / ignore; valid (N,) bool, False for points excluded from evaluation
    (e.g. ScanNet++'s ignore mask).
    """

    scene_id: str
    coord: np.ndarray
    color: np.ndarray
    normal: np.ndarray
    instance: np.ndarray
    segment: np.ndarray
    valid: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.coord)
        _check_array(self.coord, "coord", 2, 3, np.float32)
        _check_array(self.color, "color", 2, 3, np.uint8)
        _check_array(self.normal, "normal", 2, 3, np.float32)
        _check_array(self.instance, "instance", 1, None, np.int32)
        _check_array(self.segment, "segment", 1, None, np.int32)
        _check_array(self.valid, "valid", 1, None, np.bool_)
        for name in ("color", "normal", "instance", "segment", "valid"):
            if len(getattr(self, name)) != n:
                raise ValueError(f"{name}: {len(getattr(self, name))} rows for {n} points")
        _freeze(self.coord, self.color, self.normal, self.instance, self.segment, self.valid)

    def __len__(self) -> int:
        return len(self.coord)
