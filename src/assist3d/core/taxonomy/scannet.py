"""ScanNet's class ids for the generator's classes: the ScanNet-20 and ScanNet200 label of every
class name, so that stacks trained on ScanNet (Pointcept's ``segment20`` / ``segment200``, the
``scannetv2-labels.combined.tsv`` label map, Mask3D's label database) read our scenes.

A class name is matched to ScanNet200 with the rules of :mod:`.classes` (normalisation, synonyms,
head noun); its ScanNet-20 class is the one of that ScanNet200 class's NYU40 id. Where ScanNet's
own table drops an object (NYU40 ids outside the 20, e.g. "otherprop") and where no name matches,
the object is ``otherfurniture`` in ScanNet-20, so that every object of a scene is an instance a
ScanNet-20 configuration trains on; an unmatched name is ``object`` in ScanNet200. The room's
surfaces are ``wall``, ``floor`` and ``ceiling`` (ScanNet-20 has no ceiling class: -1 there, as
in ScanNet). docs/ecosystem.md has the table for the built-in classes.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from importlib import resources

from .classes import builtin_class_list

__all__ = ["SCANNET20_NAMES", "SCANNET20_NYU40", "SCANNET200_OTHER", "SCANNET20_OTHER", "SURFACES",
           "ScanNet200Class", "ScanNetLabel", "scannet200_classes", "scannet_label", "surface_label"]

#: The 20 ScanNet benchmark classes, in the order of a ``segment20`` index.
SCANNET20_NAMES: tuple[str, ...] = (
    "wall", "floor", "cabinet", "bed", "chair", "sofa", "table", "door", "window", "bookshelf", "picture",
    "counter", "desk", "curtain", "refrigerator", "shower curtain", "toilet", "sink", "bathtub", "otherfurniture")
#: Their NYU40 ids (the ``nyu40id`` column of ScanNet's label map).
SCANNET20_NYU40: tuple[int, ...] = (1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 14, 16, 24, 28, 33, 34, 36, 39)
#: ScanNet-20 index of an object with no ScanNet-20 class ("otherfurniture").
SCANNET20_OTHER = SCANNET20_NAMES.index("otherfurniture")
#: ScanNet200 class of a name that matches none of its classes.
SCANNET200_OTHER = "object"
#: The room's surfaces, in the order of :func:`surface_label`'s codes (0 wall, 1 floor, 2 ceiling).
SURFACES: tuple[str, ...] = ("wall", "floor", "ceiling")


@dataclass(frozen=True)
class ScanNet200Class:
    """One ScanNet200 class: ``index`` 0-199 (a ``segment200`` value), ``id`` (ScanNet's label id),
    ``name`` and the NYU40 id and class ScanNet's label map gives it."""

    index: int
    id: int
    name: str
    nyu40id: int
    nyu40class: str


@dataclass(frozen=True)
class ScanNetLabel:
    """What ScanNet calls one of our classes: its ScanNet200 class, its ScanNet-20 index (-1 =
    none, the ceiling only) and the NYU40 id that goes with that index in our label map
    (``nyu40id``; a function of the ScanNet200 class), and whether the name matched (False:
    ``object`` / ``otherfurniture``)."""

    name: str
    scannet200: ScanNet200Class
    index20: int
    nyu40id: int
    matched: bool

    @property
    def name20(self) -> str:
        return SCANNET20_NAMES[self.index20] if self.index20 >= 0 else ""


@lru_cache(maxsize=None)
def scannet200_classes() -> tuple[ScanNet200Class, ...]:
    """The 200 ScanNet200 classes in ``segment200`` order (resources/classes/scannet200_ids.tsv)."""
    text = resources.files("assist3d").joinpath("resources", "classes", "scannet200_ids.tsv").read_text(encoding="utf-8")
    out = []
    for line in text.splitlines():
        if line.strip() and not line.startswith("#"):
            index, cid, name, nyu, nyu_class = line.split("\t")
            out.append(ScanNet200Class(int(index), int(cid), name, int(nyu), nyu_class))
    return tuple(out)


@lru_cache(maxsize=None)
def _by_name() -> dict[str, ScanNet200Class]:
    return {c.name: c for c in scannet200_classes()}


def _index20(nyu40id: int) -> int:
    return SCANNET20_NYU40.index(nyu40id) if nyu40id in SCANNET20_NYU40 else -1


@lru_cache(maxsize=4096)
def scannet_label(class_name: str) -> ScanNetLabel:
    """The ScanNet labels of an object class (see the module docstring for the rules)."""
    hit = builtin_class_list("scannet200").match(class_name)
    if hit is not None and hit not in SURFACES:  # an object is never the room's wall, floor or ceiling
        c = _by_name()[hit]
        i20 = _index20(c.nyu40id)
        if i20 < 2:  # an object never counts as wall or floor ("shower wall", "shower floor"), nor void
            i20 = SCANNET20_OTHER
        return ScanNetLabel(class_name, c, i20, SCANNET20_NYU40[i20], True)
    other = _by_name()[SCANNET200_OTHER]
    return ScanNetLabel(class_name, other, SCANNET20_OTHER, SCANNET20_NYU40[SCANNET20_OTHER], False)


def surface_label(code: int) -> ScanNetLabel:
    """The ScanNet labels of a room surface: ``code`` 0 wall, 1 floor, 2 ceiling (:data:`SURFACES`)."""
    c = _by_name()[SURFACES[code]]
    return ScanNetLabel(c.name, c, _index20(c.nyu40id), c.nyu40id, True)
