"""Target class lists of real datasets and the matching of asset classes to them.

The complementary selection strategy restricts some draws to assets whose class exists in a real
dataset (the paper's D^r). Asset catalogs name their classes freely ("couch", "night table",
"bookcase"), so a class is matched by name through three steps:

1. normalisation: lower case, ``_``/``-`` to spaces, collapsed spaces, a trailing plural ``s`` of a
   known name removed;
2. synonyms: a hand-written table mapping variants to one canonical (ScanNet200-style) name;
3. a list-specific reduction: ScanNet's 18 benchmark classes merge fine classes ("armchair",
   "office chair" -> chair; "coffee table" -> table; "nightstand" -> otherfurniture);
4. the head noun: a multi-word name falls back to its last word ("dining chair" -> chair).

``resolve_class_list("scannet18" | "scannet200" | path)`` gives a :class:`ClassList`.
"""

from __future__ import annotations

import logging
import re
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from pathlib import Path

from .. import reading
from ..errors import ConfigError

log = logging.getLogger(__name__)

BUILTIN_LISTS = ("scannet18", "scannet200")

# Variant name -> canonical name. Canonical names follow ScanNet200's vocabulary where it has one.
SYNONYMS: dict[str, str] = {
    # seating
    "couch": "sofa", "settee": "sofa", "loveseat": "sofa", "love seat": "sofa", "sectional": "sofa",
    "sectional sofa": "sofa", "corner sofa": "sofa", "divan": "sofa", "futon": "sofa",
    "arm chair": "armchair", "easy chair": "armchair", "lounge chair": "armchair", "recliner": "armchair",
    "wing chair": "armchair", "club chair": "armchair", "sofa chair": "armchair",
    "desk chair": "office chair", "swivel chair": "office chair", "computer chair": "office chair",
    "dining chair": "chair", "side chair": "chair", "kitchen chair": "chair", "folding chair": "folded chair",
    "bar stool": "stool", "barstool": "stool", "footstool": "ottoman", "pouf": "ottoman", "pouffe": "ottoman",
    "footrest": "ottoman",
    # tables
    "night table": "nightstand", "night stand": "nightstand", "bedside table": "nightstand",
    "bedside cabinet": "nightstand", "nightstands": "nightstand",
    "side table": "end table", "occasional table": "end table", "low table": "coffee table",
    "cocktail table": "coffee table", "kitchen table": "dining table", "round table": "table",
    "work desk": "desk", "writing desk": "desk", "computer desk": "desk", "office desk": "desk",
    "tv table": "tv stand", "tv cabinet": "tv stand", "tv unit": "tv stand", "media console": "tv stand",
    "entertainment center": "tv stand",
    # storage
    "bookcase": "bookshelf", "book shelf": "bookshelf", "book case": "bookshelf", "shelving": "shelf",
    "shelves": "shelf", "shelving unit": "shelf", "wall shelf": "shelf", "etagere": "shelf",
    "cupboard": "cabinet", "sideboard": "cabinet", "buffet": "cabinet", "credenza": "cabinet",
    "chest": "dresser", "chest of drawers": "dresser", "commode": "dresser", "drawers": "dresser",
    "armoire": "wardrobe", "closet": "wardrobe", "filing cabinet": "file cabinet",
    "wall cabinet": "kitchen cabinet", "upper cabinet": "kitchen cabinet",
    # appliances
    "fridge": "refrigerator", "freezer": "refrigerator", "minifridge": "mini fridge",
    "washer": "washing machine", "dryer": "clothes dryer", "cooker": "stove", "hob": "stove",
    "television": "tv", "tv set": "tv", "flat screen": "tv", "computer monitor": "monitor", "screen": "monitor",
    "display": "monitor", "pc": "computer tower", "computer": "computer tower", "notebook computer": "laptop",
    "phone": "telephone", "loudspeaker": "speaker", "speakers": "speaker", "kettle": "coffee kettle",
    "hood": "range hood", "extractor hood": "range hood", "heater": "radiator",
    # bath
    "wc": "toilet", "lavatory": "toilet", "washbasin": "sink", "wash basin": "sink", "basin": "sink",
    "bath": "bathtub", "bath tub": "bathtub", "tub": "bathtub", "vanity": "bathroom vanity",
    "shower stall": "shower", "shower cabin": "shower",
    # wall items
    "painting": "picture", "frame": "picture", "picture frame": "picture", "photo": "picture",
    "photograph": "picture", "artwork": "picture", "canvas": "picture", "wall art": "picture",
    "wall clock": "clock", "chalkboard": "blackboard", "pinboard": "bulletin board", "corkboard": "bulletin board",
    "drapes": "curtain", "drape": "curtain", "curtains": "curtain", "blind": "blinds",
    # lights
    "floor lamp": "lamp", "table lamp": "lamp", "desk lamp": "lamp", "standing lamp": "lamp",
    "lampshade": "lamp", "wall lamp": "light", "sconce": "light", "wall light": "light",
    "chandelier": "ceiling light", "pendant lamp": "ceiling light", "ceiling lamp": "ceiling light",
    # small things
    "houseplant": "potted plant", "flowerpot": "potted plant", "flower pot": "potted plant", "pot plant": "plant",
    "flowers": "plant", "tree": "plant", "mug": "cup", "glass": "cup", "tumbler": "cup",
    "dish": "plate", "books": "book", "magazine": "book", "garbage can": "trash can", "waste bin": "trash can",
    "wastebasket": "trash can", "dustbin": "trash can", "rubbish bin": "trash can", "trashcan": "trash can",
    "computer mouse": "mouse", "bed frame": "bed", "double bed": "bed", "single bed": "bed", "bunk bed": "bed",
    "crib": "bed", "cot": "bed", "carpet": "mat", "rug": "mat", "doormat": "mat", "pillows": "pillow",
    "throw pillow": "pillow", "cushions": "cushion", "vase": "decoration", "sculpture": "decoration",
    "statue": "decoration", "figurine": "decoration", "ornament": "decoration", "candlestick": "candle",
    "hatstand": "coat rack", "coat stand": "coat rack", "hat stand": "coat rack", "suitcases": "suitcase",
}

# ScanNet's 18 benchmark classes merge fine classes (NYU40-based mapping of ScanNet labels).
SCANNET18_REDUCTION: dict[str, str] = {
    "armchair": "chair", "office chair": "chair", "folded chair": "chair", "seat": "chair",
    "couch": "sofa", "coffee table": "table", "end table": "table", "dining table": "table",
    "kitchen cabinet": "cabinet", "file cabinet": "cabinet", "bathroom cabinet": "cabinet",
    "bathroom vanity": "cabinet", "wardrobe": "cabinet", "tv stand": "cabinet",
    "kitchen counter": "counter", "bathroom counter": "counter", "mini fridge": "refrigerator",
    "poster": "picture", "shelf": "bookshelf", "closet door": "door", "shower door": "door",
    "blinds": "curtain", "shower curtain rod": "shower curtain",
    "nightstand": "otherfurniture", "dresser": "otherfurniture", "stool": "otherfurniture",
    "ottoman": "otherfurniture", "bench": "otherfurniture", "piano": "otherfurniture",
    "washing machine": "otherfurniture", "clothes dryer": "otherfurniture", "dishwasher": "otherfurniture",
    "stove": "otherfurniture", "oven": "otherfurniture", "fireplace": "otherfurniture",
    "coat rack": "otherfurniture", "rack": "otherfurniture", "stand": "otherfurniture",
    "cart": "otherfurniture", "furniture": "otherfurniture", "ladder": "otherfurniture",
    "trash can": "otherfurniture", "recycling bin": "otherfurniture", "water cooler": "otherfurniture",
    "copier": "otherfurniture", "printer": "otherfurniture", "radiator": "otherfurniture",
}

_REDUCTIONS: dict[str, dict[str, str]] = {"scannet18": SCANNET18_REDUCTION}


def normalise_class(name: str) -> str:
    """Lower case, ``_``/``-``/``/`` to spaces, collapsed whitespace."""
    return re.sub(r"\s+", " ", re.sub(r"[_\-/]+", " ", str(name).lower())).strip()


def canonical_class(name: str) -> str:
    """The canonical name of an asset class (normalised, then through :data:`SYNONYMS`)."""
    n = normalise_class(name)
    if n in SYNONYMS:
        return SYNONYMS[n]
    if n.endswith("s") and n[:-1] in SYNONYMS:
        return SYNONYMS[n[:-1]]
    return n


@dataclass(frozen=True)
class ClassList:
    """A target class list and its name-matching rules."""

    name: str
    classes: tuple[str, ...]
    reduction: dict = field(default_factory=dict, compare=False, hash=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_key", tuple(sorted(self.reduction.items())))

    def match(self, asset_class: str) -> str | None:
        """The class of this list an asset class counts as, or ``None``."""
        return _match_cached(self.name, self.classes, self._key, asset_class)  # type: ignore[attr-defined]

    def __contains__(self, asset_class: str) -> bool:
        return self.match(asset_class) is not None

    def __len__(self) -> int:
        return len(self.classes)


@lru_cache(maxsize=65536)
def _match_cached(name: str, classes: tuple[str, ...], reduction: tuple, asset_class: str) -> str | None:
    members = {c: c for c in classes}
    by_canon: dict[str, str] = {}
    for c in classes:
        by_canon.setdefault(canonical_class(c), c)
    reduce = dict(reduction)

    def one(n: str) -> str | None:
        for cand in (n, n[:-1] if n.endswith("s") else ""):
            if not cand:
                continue
            if cand in members:
                return cand
            c = canonical_class(cand)
            if c in members:
                return c
            if c in by_canon:
                return by_canon[c]
            r = reduce.get(c)
            if r in members:
                return r
        return None

    n = normalise_class(asset_class)
    hit = one(n)
    if hit is None and " " in n:
        hit = one(n.rsplit(" ", 1)[1])  # head noun: "dining chair" -> chair
    return hit


def _parse_lines(text: str) -> tuple[str, ...]:
    out: list[str] = []
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            n = normalise_class(line)
            if n not in out:
                out.append(n)
    return tuple(out)


@lru_cache(maxsize=None)
def builtin_class_list(name: str) -> ClassList:
    """ScanNet's 18 benchmark classes (``scannet18``) or ScanNet200's 198 object classes."""
    if name not in BUILTIN_LISTS:
        raise ConfigError(f"unknown class list {name!r}; expected one of {BUILTIN_LISTS} or a text file path")
    text = resources.files("assist3d").joinpath("resources", "classes", f"{name}.txt").read_text(encoding="utf-8")
    return ClassList(name, _parse_lines(text), _REDUCTIONS.get(name, {}))


def resolve_class_list(spec: str) -> ClassList:
    """``"scannet18"``, ``"scannet200"``, or a path to a text file with one class per line."""
    if spec in BUILTIN_LISTS:
        return builtin_class_list(spec)
    p = Path(spec).expanduser()
    if not p.is_file():
        raise ConfigError(f"selection.real_classes: {spec!r} is neither a built-in list {BUILTIN_LISTS} "
                          f"nor an existing text file (one class per line)")
    classes = _parse_lines(reading.read_text(p, error=ConfigError, what="class list"))
    if not classes:
        raise ConfigError(f"{p}: class list is empty (expected one class name per line)")
    return ClassList(p.stem, classes, {})
