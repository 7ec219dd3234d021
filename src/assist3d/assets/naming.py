"""Class names and groups of imported assets (shared by the Sweet Home 3D and mesh importers).

``class_from_name`` turns a catalog name such as ``"Bed 140x190"``, ``"Concept Sedan 02"`` or
``"Blue light source"`` into a normalised lower-case class (``"bed"``, ``"concept sedan"``,
``"light source"``). ``assign_groups`` decides the groups ``floor``/``wall``/``obj`` from the size,
the elevation and wall-hung words in the name or category.
"""

from __future__ import annotations

import re
import unicodedata
from typing import Sequence

COLOURS = frozenset({
    "black", "white", "blue", "red", "green", "magenta", "yellow", "orange", "pink", "purple", "brown",
    "grey", "gray", "beige", "cyan", "violet", "golden", "silver",
})
# plural words that are not the plural of a (different) singular class
KEEP_PLURAL = frozenset({
    "glasses", "sunglasses", "clothes", "scissors", "pliers", "headphones", "trousers", "jeans", "shorts",
    "pants", "stairs", "tongs", "binoculars", "news", "chess", "bus", "cactus", "lotus", "octopus",
    "hibiscus", "asparagus", "citrus", "grass", "glass", "dress", "mattress", "compass", "press",
})
_SIZE = re.compile(r"\b\d+(?:[.,]\d+)?\s*(?:x\s*\d+(?:[.,]\d+)?)+\s*(?:cm|mm|m)?\b", re.I)
_NUM = re.compile(r"\b\d+(?:[.,:]\d+)*\s*(?:cm|mm|m|°|\u00b0|€|\$|%)?(?=\s|$)|[°\u00b0€$%]", re.I)
_PAREN = re.compile(r"\([^)]*\)|\[[^\]]*\]")
_SEP = re.compile(r"[_\-/,;+&#]+")
_SPACE = re.compile(r"\s+")
# phrases whose colour word is part of the class
PHRASES = {"white board": "whiteboard", "black board": "blackboard", "blackboard": "blackboard"}

# wall-hung / wall-mounted things (matched as whole words or phrases in the lower-case name)
WALL_WORDS = (
    "picture", "painting", "poster", "frame", "mirror", "clock", "radiator", "wall", "plug", "socket",
    "switch", "upper cabinet", "upper corner cabinet", "upper shelves", "hood", "towel rack", "towel",
    "paper towel holder", "toilet paper dispenser", "calendar", "white board", "whiteboard", "curtain",
    "curtains", "blind", "shutter", "intercom", "bell ring", "speech unit", "emergency sign",
    "air conditioning", "boiler", "water heater", "basketball net", "dart", "extinguisher", "hanger",
    "thermometer", "cctv", "surveillance camera", "spotlight", "number lock", "letters box",
    "mailbox", "shower head", "urinal", "wall shelf", "tv on wall", "wall flat tv", "fuse box",
)
CEILING_WORDS = (
    "ceiling", "chandelier", "pendant", "hanging light", "track lights", "fluorescent light",
    "light source", "smoke detector",
)
WALL_CATEGORIES = ("wall", "paintings", "pictures", "decoration - wall")
WALL_ELEVATION_M = 0.3  # above this base height an item hangs on a wall (or the ceiling)
SMALL_SIDE_M = 0.6  # an item fits on top of others if its footprint and height are at most this
SMALL_FLOOR_SIDE_M = 0.3  # a small item also stands on the floor if it is at least this tall or wide


def _words_pattern(words: Sequence[str]) -> re.Pattern[str]:
    alts = "|".join(re.escape(w) for w in sorted(words, key=len, reverse=True))
    return re.compile(rf"(?<![a-z])(?:{alts})(?![a-z])")


_WALL_RE = _words_pattern(WALL_WORDS)
_CEILING_RE = _words_pattern(CEILING_WORDS)


def singular(word: str) -> str:
    """A simple English singular of one lower-case word (``shelves`` -> ``shelf``)."""
    w = word
    if len(w) <= 3 or w in KEEP_PLURAL or w.endswith(("ss", "us", "is", "ous")):
        return w
    if w.endswith("ies") and len(w) > 4:
        return w[:-3] + "y"
    if w.endswith("ves") and w[:-3] in ("shel", "hal", "lea", "wol", "loa", "cal", "el"):
        return w[:-3] + "f"
    if w.endswith("ves") and w[:-3] in ("kni", "li", "wi"):
        return w[:-3] + "fe"
    if w.endswith(("ches", "shes", "xes", "sses", "zes")):
        return w[:-2]
    if w.endswith("oes") and w not in ("shoes",):
        return w[:-2]
    if w.endswith("s") and not w.endswith("'s"):
        return w[:-1]
    return w


def _ascii(s: str) -> str:
    return unicodedata.normalize("NFKD", s).encode("ascii", "ignore").decode("ascii")


def class_from_name(name: str, *, fallback: str = "object") -> str:
    """Normalised lower-case class of a catalog name.

    Drops bracketed notes, sizes (``140x190``), numbers with units (``45°``, ``10€``, ``16:9``),
    colour words, short upper-case suffix codes (``BZ``, ``CC``: model codes, not classes) and
    accents; turns separators into spaces and singularises the last word. Returns ``fallback``
    when nothing is left.
    """
    s = _PAREN.sub(" ", name)
    for phrase, word in PHRASES.items():
        s = re.sub(rf"(?i)\b{re.escape(phrase)}\b", word, s)
    s = _SIZE.sub(" ", s)
    s = _NUM.sub(" ", s)
    s = _SEP.sub(" ", s)
    tokens = [t for t in _SPACE.split(s.strip()) if t]
    # trailing model codes written in capitals ("Convertible sofa BZ", "Peugeot 308 CC"), not "TV"
    while len(tokens) > 1 and re.fullmatch(r"[A-Z]{1,3}\d*", tokens[-1]) and tokens[-1] not in ("TV", "DVD", "SUV", "PC"):
        tokens.pop()
    tokens = [_ascii(t).lower().strip(".'") for t in tokens]
    tokens = [t for t in tokens if t and any(ch.isalpha() for ch in t)]
    no_colour = [t for t in tokens if t not in COLOURS]
    if no_colour:
        tokens = no_colour
    if not tokens:
        return fallback
    tokens[-1] = singular(tokens[-1])
    return " ".join(tokens)


def wall_mount(name: str, category: str = "") -> str | None:
    """``'ceiling'`` or ``'wall'`` when the name/category says the item hangs, else None."""
    text = f"{name} ".lower()
    if _CEILING_RE.search(text):
        return "ceiling"
    if _WALL_RE.search(text) or category.strip().lower() in WALL_CATEGORIES:
        return "wall"
    return None


def assign_groups(size: Sequence[float], *, elevation: float = 0.0, name: str = "", category: str = "") -> tuple[str, ...]:
    """Groups of an asset from its canonical size (w, d, h) metres, base elevation and words.

    * ``wall``: elevation above :data:`WALL_ELEVATION_M`, or a wall-/ceiling-hung name; wall items
      are in no other group.
    * ``obj``: footprint and height at most :data:`SMALL_SIDE_M` (fits on a table or shelf).
    * ``floor``: everything else that is not wall-hung, and small items that are at least
      :data:`SMALL_FLOOR_SIDE_M` tall or wide (a plant, a bin, a child's chair).
    """
    w, d, h = (float(x) for x in size)
    if elevation > WALL_ELEVATION_M or wall_mount(name, category):
        return ("wall",)
    small = max(w, d) <= SMALL_SIDE_M and h <= SMALL_SIDE_M
    if not small:
        return ("floor",)
    if h >= SMALL_FLOOR_SIDE_M or max(w, d) >= SMALL_FLOOR_SIDE_M:
        return ("floor", "obj")
    return ("obj",)
