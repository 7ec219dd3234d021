"""Room-type object lists: what an LLM asked for "a bedroom" or "a kitchen" keeps choosing.

This is the object-selection side of the Holodeck-style baseline (``selection.strategy:
room-type``, preset ``holodeck-style``). Holodeck prompts an LLM with a room type; the LLM answers
with the room's objects, each with a quantity and whether the copies are identical
(``variance_type: same``) or varied, then small objects for the surfaces, and every object is
retrieved from Objaverse by text similarity, which returns the same few models for "a bed" in
every bedroom. The tables below are that answer written down, one :class:`RoomTemplate` per room
type: the anchors every such room gets (bed, toilet, dining table), the usual companions with the
probability that a room has them, the quantities (four to six identical dining chairs), the wall
objects and the small objects of the room. Retrieval is modelled by ``selection.assets_per_class``
(a fixed few models per class).

Class names are canonical (:func:`assist3d.core.taxonomy.classes.canonical_class`); an item matches every
asset whose class or canonical class is the item's class. Every class here is produced by the
built-in procedural library (a test checks); other catalogs may lack some, which are then skipped
and counted (``template_misses`` in the selection stats).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Item:
    """One line of a room's object list.

    ``prob``: probability that a room of this type has the item; ``count``: inclusive range of its
    quantity; ``same``: the copies are one model repeated (else each copy is drawn anew);
    ``per``: the quantity is one per selected item of that class instead (an office chair per
    desk); ``needs``: only with an item of that class in the room; ``holds``: small objects may be
    put on it (False for seats, beds and fixtures: nobody puts a vase on a dining chair)."""

    cls: str
    prob: float = 1.0
    count: tuple[int, int] = (1, 1)
    same: bool = True
    per: str | None = None
    needs: str | None = None
    holds: bool = True


@dataclass(frozen=True)
class RoomTemplate:
    """The object list of one room type: floor items, wall items, and the classes of its small
    objects (drawn for every support surface, ``selection.on_top_count`` per support)."""

    floor: tuple[Item, ...]
    wall: tuple[Item, ...]
    small: tuple[str, ...]

    def classes(self) -> set[str]:
        return {i.cls for i in self.floor} | {i.cls for i in self.wall} | set(self.small)


ROOM_TEMPLATES: dict[str, RoomTemplate] = {
    "bedroom": RoomTemplate(
        floor=(Item("bed", holds=False), Item("nightstand", 0.9, (1, 2)), Item("wardrobe", 0.8),
               Item("dresser", 0.6), Item("lamp", 0.5, holds=False), Item("desk", 0.3),
               Item("office chair", per="desk", holds=False), Item("armchair", 0.2, holds=False),
               Item("plant", 0.3, holds=False), Item("trash can", 0.3, holds=False)),
        wall=(Item("picture", 0.9, (1, 3), same=False, holds=False), Item("curtain", 0.7, holds=False),
              Item("mirror", 0.5, holds=False), Item("clock", 0.3, holds=False)),
        small=("pillow", "book", "alarm clock", "lamp", "vase", "cup", "phone", "tissue box", "plant", "candle",
               "stuffed animal"),
    ),
    "living room": RoomTemplate(
        floor=(Item("sofa", holds=False), Item("coffee table"), Item("armchair", 0.8, (1, 2), holds=False),
               Item("tv stand", 0.9), Item("end table", 0.6, (1, 2)), Item("bookshelf", 0.6),
               Item("plant", 0.6, (1, 2), same=False, holds=False), Item("lamp", 0.6, holds=False),
               Item("ottoman", 0.3, holds=False), Item("shelf", 0.3)),
        wall=(Item("tv", 0.8, holds=False), Item("picture", 0.9, (1, 3), same=False, holds=False),
              Item("curtain", 0.7, holds=False), Item("clock", 0.4, holds=False), Item("mirror", 0.2, holds=False)),
        small=("vase", "book", "remote control", "plant", "cup", "mug", "bowl", "candle", "tray", "sculpture",
               "speaker", "fruit bowl", "game controller"),
    ),
    "dining room": RoomTemplate(
        floor=(Item("dining table"), Item("chair", 1.0, (4, 6), holds=False), Item("cabinet", 0.6),
               Item("shelf", 0.4), Item("plant", 0.5, holds=False), Item("lamp", 0.3, holds=False)),
        wall=(Item("picture", 0.8, (1, 2), same=False, holds=False), Item("clock", 0.5, holds=False),
              Item("mirror", 0.3, holds=False), Item("curtain", 0.6, holds=False)),
        small=("plate", "bowl", "cup", "glass", "vase", "fruit bowl", "wine bottle", "candle", "bottle", "teapot",
               "tray"),
    ),
    "kitchen": RoomTemplate(
        floor=(Item("counter", 1.0, (1, 3)), Item("refrigerator", holds=False), Item("stove", 0.9, holds=False),
               Item("sink", 0.9, holds=False), Item("dishwasher", 0.5), Item("table", 0.5),
               Item("chair", 1.0, (2, 4), needs="table", holds=False), Item("stool", 0.3, (2, 3), holds=False),
               Item("trash can", 0.7, holds=False)),
        wall=(Item("kitchen cabinet", 1.0, (2, 4)), Item("clock", 0.4, holds=False),
              Item("paper towel dispenser", 0.3, holds=False), Item("shelf", 0.3)),
        small=("microwave", "kettle", "toaster", "coffee maker", "blender", "pot", "pan", "cutting board", "bowl",
               "plate", "cup", "mug", "bottle", "jar", "fruit bowl"),
    ),
    "bathroom": RoomTemplate(
        floor=(Item("toilet", holds=False), Item("sink", holds=False), Item("bathtub", 0.6, holds=False),
               Item("shower", 0.4, holds=False), Item("cabinet", 0.4), Item("trash can", 0.6, holds=False),
               Item("laundry basket", 0.3, holds=False)),
        wall=(Item("mirror", holds=False), Item("towel", 0.8, (1, 2), holds=False), Item("bathroom cabinet", 0.5),
              Item("soap dispenser", 0.4, holds=False), Item("shower curtain", 0.3, holds=False)),
        small=("soap bottle", "toilet paper", "spray bottle", "bottle", "cup", "tissue box", "vase", "candle"),
    ),
    "office": RoomTemplate(
        floor=(Item("desk", 1.0, (1, 2)), Item("office chair", per="desk", holds=False), Item("bookshelf", 0.7),
               Item("file cabinet", 0.6), Item("cabinet", 0.3), Item("plant", 0.5, holds=False),
               Item("trash can", 0.7, holds=False)),
        wall=(Item("whiteboard", 0.5, holds=False), Item("picture", 0.6, (1, 2), same=False, holds=False),
              Item("clock", 0.5, holds=False), Item("bulletin board", 0.4, holds=False), Item("shelf", 0.3)),
        small=("monitor", "keyboard", "computer mouse", "laptop", "book", "binder", "pen holder", "stapler", "phone",
               "mug", "lamp", "paper", "printer", "headphones"),
    ),
}


def template_classes() -> tuple[str, ...]:
    """Every class named by a room template, sorted."""
    return tuple(sorted(set().union(*(t.classes() for t in ROOM_TEMPLATES.values()))))
