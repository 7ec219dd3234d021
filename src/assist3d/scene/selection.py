"""Heterogeneous object selection (paper section "Heterogeneous Object Selection").

Per scene: M1 floor assets and M2 wall assets drawn uniformly, then K on-top assets for every
selected object that has a support surface. Two strategies alternate between scenes:

* **random**: every draw is uniform over the group's pool;
* **complementary**: each draw is restricted, with probability p (``real_class_prob``), to assets
  whose class matches the target real dataset's class list (``real_classes``), provided the pool
  holds at least ``min_real_classes`` such classes (else the restriction would turn most draws of,
  e.g., the on-top pool into copies of ScanNet18's only small class, "picture").

"Uniform" is, by default, uniform over classes and then over the assets of the drawn class
(``sampling: class``), so a class with a hundred near-identical models does not crowd out the rest;
``sampling: asset`` draws uniformly over assets instead. Within a scene assets are drawn without
replacement until a class (or the pool) runs out, then with replacement.

On-top draws for a support are, by default (``on_top_fit``), taken among the on-top assets whose
box fits one of its surfaces (footprint either way round, height under the clearance): a drawer
cannot hold a television, and drawing one only to drop it wastes the search budget.

``strategy: room-type`` replaces the random floor and wall draws by a Holodeck-style room: a room
type drawn per scene and its typical object list (:mod:`assist3d.core.taxonomy.roomtypes`), with on-top
draws restricted to the room's small-object classes.

Ablation controls: ``pairing_prob`` q co-selects each drawn class's partner class, ``clusters``
keeps only some shape clusters, ``allowed_classes`` and ``max_classes`` restrict the class pool,
``assets_per_class`` keeps a fixed few models per class (retrieval-style baselines).
"""

from __future__ import annotations

import logging
import threading
import weakref
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..assets.catalog import Catalog
from ..config import SelectionConfig
from ..core.contracts import AssetRecord
from ..core.errors import ConfigError
from ..core.rng import make_rng
from ..core.taxonomy.classes import ClassList, canonical_class, normalise_class, resolve_class_list
from ..core.taxonomy.roomtypes import ROOM_TEMPLATES, Item, RoomTemplate

log = logging.getLogger(__name__)

# Typical co-occurring partners (canonical names); used in both directions unless a class has its
# own entry. Classes with no partner here (or whose partner has no asset in the pool) are paired at
# random with ``class_pool_seed``.
PARTNERS: tuple[tuple[str, str], ...] = (
    ("table", "chair"), ("dining table", "chair"), ("desk", "office chair"), ("bed", "nightstand"),
    ("sofa", "coffee table"), ("armchair", "end table"), ("tv stand", "tv"), ("toilet", "sink"),
    ("bathtub", "towel"), ("monitor", "keyboard"), ("keyboard", "mouse"), ("laptop", "mouse"),
    ("counter", "stool"), ("kitchen counter", "stool"), ("bookshelf", "book"), ("shelf", "book"),
    ("refrigerator", "kitchen cabinet"), ("stove", "range hood"), ("dresser", "mirror"),
    ("wardrobe", "dresser"), ("piano", "bench"), ("cup", "plate"), ("bowl", "plate"), ("lamp", "nightstand"),
    ("picture", "clock"), ("washing machine", "clothes dryer"), ("sink", "mirror"), ("plant", "potted plant"),
    ("bottle", "cup"), ("book", "lamp"), ("pillow", "blanket"), ("trash can", "recycling bin"),
)


@dataclass(frozen=True)
class Selection:
    """The assets selected for one scene.

    ``floor_on_top[i]`` are the on-top assets drawn for ``floor[i]`` (empty when it has no support
    surface); likewise ``wall_on_top`` for ``wall``.
    """

    floor: tuple[AssetRecord, ...]
    wall: tuple[AssetRecord, ...]
    floor_on_top: tuple[tuple[AssetRecord, ...], ...]
    wall_on_top: tuple[tuple[AssetRecord, ...], ...]
    complementary: bool
    stats: dict = field(default_factory=dict)

    @property
    def count(self) -> int:
        return len(self.floor) + len(self.wall) + sum(map(len, self.floor_on_top)) + sum(map(len, self.wall_on_top))


def _pick_fresh(members: tuple[AssetRecord, ...], rng: np.random.Generator, used: set[str]) -> AssetRecord:
    """One of ``members`` uniformly, preferring those not ``used`` yet in this scene; marks it used."""
    fresh = [r for r in members if r.id not in used]
    pick = fresh if fresh else members
    rec = pick[int(rng.integers(len(pick)))]
    used.add(rec.id)
    return rec


class _Pool:
    """The assets of one group after filtering, indexed by class."""

    def __init__(self, records: tuple[AssetRecord, ...]):
        self.records = records
        by_class: dict[str, list[AssetRecord]] = {}
        for r in records:
            by_class.setdefault(r.class_name, []).append(r)
        self.classes = tuple(sorted(by_class))
        self.by_class = {c: tuple(v) for c, v in by_class.items()}
        self._by_name: dict[str, tuple[str, ...]] | None = None  # built on first use (room-type only)
        self._models: dict[tuple, tuple[AssetRecord, ...]] = {}

    def matching(self, name: str) -> tuple[str, ...]:
        """The pool's classes whose name or canonical name is ``name`` (a canonical class name)."""
        if self._by_name is None:
            by_name: dict[str, tuple[str, ...]] = {}
            for c in self.classes:
                for key in {normalise_class(c), canonical_class(c)}:
                    by_name[key] = by_name.get(key, ()) + (c,)
            self._by_name = by_name
        return self._by_name.get(normalise_class(name), ())

    def qualified(self, name: str) -> tuple[str, ...]:
        """The pool's classes that name a kind of ``name``: their name ends with it as whole words
        ("coffee mug" for "mug", "wall flat tv" for "tv"; not "wine bottle" for "soap bottle")."""
        want = normalise_class(name)
        return tuple(c for c in self.classes if normalise_class(c).endswith(" " + want))

    def item_models(self, name: str, n: int | None, seed: int) -> tuple[AssetRecord, ...]:
        """What a text retrieval for ``name`` returns, the same in every scene: the assets of every
        matching class, or of the classes naming a kind of it when none matches (sorted by id), or
        a seeded, fixed ``n`` of them."""
        key = (name, n, seed)
        if key not in self._models:
            classes = self.matching(name) or self.qualified(name)
            recs = sorted((r for c in classes for r in self.by_class[c]), key=lambda r: r.id)
            if n is not None and len(recs) > n:
                keep = make_rng(seed, "retrieval", normalise_class(name)).permutation(len(recs))[:n]
                recs = [recs[int(i)] for i in sorted(keep)]
            self._models[key] = tuple(recs)
        return self._models[key]

    def __bool__(self) -> bool:
        return bool(self.records)

    def draw(self, rng: np.random.Generator, sampling: str, used: set[str]) -> AssetRecord:
        """A class uniformly then one of its assets ('class'), or an asset uniformly ('asset');
        assets not used yet in this scene first."""
        if sampling == "class":
            return self.draw_asset(self.classes[int(rng.integers(len(self.classes)))], rng, used)
        return _pick_fresh(self.records, rng, used)

    def draw_asset(self, cls: str, rng: np.random.Generator, used: set[str]) -> AssetRecord:
        return _pick_fresh(self.by_class[cls], rng, used)


class _PoolCache:
    """Filtered pools and support-fit sub-pools of one catalog, reused across scenes.

    Keyed weakly by the catalog and reset when its record tuple changes (an import added assets)."""

    def __init__(self) -> None:
        self._by_catalog: "weakref.WeakKeyDictionary[Catalog, tuple[tuple, dict]]" = weakref.WeakKeyDictionary()
        self._lock = threading.Lock()

    def get(self, catalog: Catalog, key: tuple, build):
        records = catalog.records
        with self._lock:
            entry = self._by_catalog.get(catalog)
            if entry is None or entry[0] is not records:
                entry = (records, {})
                self._by_catalog[catalog] = entry
            table = entry[1]
            if key in table:
                return table[key]
        value = build()
        with self._lock:
            if len(table) > 20000:
                table.clear()
            table[key] = value
        return value


_CACHE = _PoolCache()


def _filter_key(cfg: SelectionConfig) -> tuple:
    return (cfg.min_real_classes, tuple(cfg.allowed_classes) if cfg.allowed_classes is not None else None, cfg.max_classes,
            tuple(cfg.clusters) if cfg.clusters is not None else None, cfg.class_pool_seed, cfg.assets_per_class)


def is_complementary(scene_index: int, fraction: float) -> bool:
    """Whether scene ``scene_index`` uses the complementary strategy: scenes alternate so that
    exactly ``floor((i+1) f) `` of the first ``i+1`` scenes are complementary (f = 0.5: 1, 3, 5...)."""
    i = int(scene_index)
    return int(np.floor((i + 1) * fraction + 1e-9)) - int(np.floor(i * fraction + 1e-9)) == 1


def _filter(records: tuple[AssetRecord, ...], cfg: SelectionConfig, catalog: Catalog) -> tuple[AssetRecord, ...]:
    out = records
    if cfg.allowed_classes is not None:
        allowed = {normalise_class(c) for c in cfg.allowed_classes} | {canonical_class(c) for c in cfg.allowed_classes}
        out = tuple(r for r in out if normalise_class(r.class_name) in allowed or canonical_class(r.class_name) in allowed)
    if cfg.max_classes is not None:
        classes = sorted({r.class_name for r in catalog.records})
        if cfg.max_classes >= len(classes):
            log.warning("selection.max_classes = %d but catalog %s has only %d classes: no restriction",
                        cfg.max_classes, catalog.root, len(classes))
        else:
            keep_idx = make_rng(cfg.class_pool_seed, "max_classes").choice(len(classes), cfg.max_classes, replace=False)
            keep = {classes[int(i)] for i in keep_idx}
            out = tuple(r for r in out if r.class_name in keep)
    if cfg.clusters is not None:
        if not any(r.cluster is not None for r in catalog.records):
            raise ConfigError(f"{catalog.root}: selection.clusters is set but no asset of this catalog has a "
                              f"shape-cluster id; assign them first with `assist3d cluster-assets --library "
                              f"{catalog.root} --k 5`, or unset selection.clusters")
        wanted = set(cfg.clusters)
        out = tuple(r for r in out if r.cluster in wanted)
    if cfg.assets_per_class is not None:
        # keep a seeded, fixed choice of n models per class of this group (the same in every
        # scene), as a retrieval-based generator that always returns the best match for "a chair"
        # does; chosen within the group, so that a class spanning groups (a plant on the floor or
        # on a table) keeps models in each
        by_class: dict[str, list[AssetRecord]] = {}
        for r in sorted(out, key=lambda r: r.id):
            by_class.setdefault(r.class_name, []).append(r)
        keep_ids: set[str] = set()
        for cls in sorted(by_class):
            recs = by_class[cls]
            order = make_rng(cfg.class_pool_seed, "assets_per_class", cls).permutation(len(recs))
            keep_ids |= {recs[int(i)].id for i in order[: cfg.assets_per_class]}
        out = tuple(r for r in out if r.id in keep_ids)
    return out


def partner_map(classes: tuple[str, ...], class_pool_seed: int, key: str) -> dict[str, str]:
    """Each class's partner within ``classes``: the hand-written :data:`PARTNERS` where the partner
    is present, else a seeded random pairing of the remaining classes."""
    canon: dict[str, list[str]] = {}
    for c in classes:
        canon.setdefault(canonical_class(c), []).append(c)
    table: dict[str, str] = {}
    for a, b in PARTNERS:
        table.setdefault(a, b)
    for a, b in PARTNERS:
        table.setdefault(b, a)
    out: dict[str, str] = {}
    for c in classes:
        p = table.get(canonical_class(c))
        if p is not None and p in canon and canon[p][0] != c:
            out[c] = canon[p][0]
    rest = [c for c in classes if c not in out]
    if len(classes) < 2:
        return out
    order = [rest[int(i)] for i in make_rng(class_pool_seed, "pairs", key).permutation(len(rest))]
    for i in range(0, len(order) - 1, 2):
        out[order[i]], out[order[i + 1]] = order[i + 1], order[i]
    if len(order) % 2 == 1:
        others = [c for c in classes if c != order[-1]]
        out[order[-1]] = others[int(make_rng(class_pool_seed, "odd", key).integers(len(others)))]
    return out


class _Drawer:
    """Draws from one pool with the scene's strategy, pairing and bookkeeping."""

    def __init__(self, pool: _Pool, real: _Pool | None, cfg: SelectionConfig, complementary: bool,
                 partners: dict[str, str], used: set[str], stats: dict):
        self.pool, self.real, self.cfg, self.complementary, self.stats = pool, real, cfg, complementary, stats
        self.partners = {c: p for c, p in partners.items() if p in pool.by_class}
        self.used = used

    def draw(self, n: int, rng: np.random.Generator) -> list[AssetRecord]:
        out: list[AssetRecord] = []
        while len(out) < n:
            source = self.pool
            if self.complementary and self.real and rng.random() < self.cfg.real_class_prob:
                source = self.real
                self.stats["real_draws"] += 1
            rec = source.draw(rng, self.cfg.sampling, self.used)
            cls = rec.class_name
            out.append(rec)
            self.stats["draws"] += 1
            partner = self.partners.get(cls)
            if partner is not None and len(out) < n and rng.random() < self.cfg.pairing_prob:
                out.append(self.pool.draw_asset(partner, rng, self.used))
                self.stats["partner_draws"] += 1
        return out


def _template_draw(pool: _Pool, items: tuple[Item, ...], rng: np.random.Generator, used: set[str],
                   stats: dict, cfg: SelectionConfig) -> tuple[list[AssetRecord], list[bool]]:
    """The assets of one room-template group: items in order, each kept with its probability,
    with its quantity (one model repeated when ``same``), drawn from the item's retrieved models
    (``assets_per_class`` of them when set, across every class matching the item); an item the
    pool has no model for is skipped and counted in ``stats["template_misses"]``. Also returns,
    per asset, whether small objects may be put on it (the item's ``holds``)."""
    out: list[AssetRecord] = []
    holds: list[bool] = []
    chosen: dict[str, int] = {}
    for it in items:
        if it.needs is not None and not chosen.get(it.needs):
            continue
        if rng.random() >= it.prob:
            continue
        n = chosen.get(it.per, 0) if it.per is not None else int(rng.integers(it.count[0], it.count[1] + 1))
        if n <= 0:
            continue
        models = pool.item_models(it.cls, cfg.assets_per_class, cfg.class_pool_seed)
        if not models:
            stats["template_misses"] += 1
            continue
        if it.same:
            out += [_pick_fresh(models, rng, used)] * n
        else:
            out += [_pick_fresh(models, rng, used) for _ in range(n)]
        holds += [it.holds] * n
        chosen[it.cls] = chosen.get(it.cls, 0) + n
    return out, holds


def fits_support_mask(parent: AssetRecord, sizes: np.ndarray) -> np.ndarray:
    """(n,) bool: which boxes (``sizes`` (n, 3) float64, w x d x h) fit on one of ``parent``'s support
    surfaces: footprint within the surface's bounding box either way round, height within its
    clearance."""
    mask = np.zeros(len(sizes), dtype=bool)
    for s in parent.supports:
        poly = np.asarray(s.polygon, dtype=np.float64)
        if len(poly) < 3:
            continue
        ew, ed = poly.max(0) - poly.min(0)
        tall = np.inf if s.clearance is None else float(s.clearance)
        w, d, h = sizes[:, 0], sizes[:, 1], sizes[:, 2]
        mask |= (((w <= ew) & (d <= ed)) | ((d <= ew) & (w <= ed))) & (h <= tall)
    return mask


def select_objects(catalog: Catalog, cfg: SelectionConfig, rng: np.random.Generator, *, scene_index: int,
                   propose: Callable[[str, dict[str, tuple[str, ...]]], tuple[RoomTemplate | None, dict]] | None = None,
                   ) -> Selection:
    """Select the assets of one scene.

    Floor draws first (M1 = ``floor_count``), then wall draws (M2 = ``wall_count``), then K =
    ``on_top_count`` on-top draws for each selected object with a support surface, in that order.
    The same ``rng`` state gives the same selection. Raises :class:`ConfigError` when the floor pool
    is empty after the filters while floor objects are requested.

    With ``strategy: room-type``, ``propose(room_type, vocabulary)`` (an LLM's object plan, see
    :meth:`assist3d.planning.llm_planner.LLMPlanner.propose_room`) may replace the built-in template of the
    drawn room type; ``vocabulary`` maps "floor", "wall" and "obj" to the pools' canonical class
    names. Its stats are kept under ``stats["room_llm"]``.
    """
    room_type: str | None = None
    if cfg.strategy == "room-type":
        names = tuple(cfg.room_types or ROOM_TEMPLATES)
        room_type = names[int(rng.integers(len(names)))]
    complementary = room_type is None and is_complementary(scene_index, cfg.complementary_fraction)
    classes: ClassList | None = resolve_class_list(cfg.real_classes) if complementary else None
    stats = {"complementary": complementary, "draws": 0, "real_draws": 0, "partner_draws": 0}
    if room_type is not None:
        stats.update(room_type=room_type, template_misses=0)
    fkey = _filter_key(cfg)
    pools = {g: _CACHE.get(catalog, ("pool", fkey, g), lambda g=g: _Pool(_filter(catalog.group(g), cfg, catalog)))
             for g in ("floor", "wall", "obj")}
    if cfg.floor_count > 0 and not pools["floor"]:
        raise ConfigError(f"{catalog.root}: no floor asset is left to select from after the selection filters "
                          f"(allowed_classes={cfg.allowed_classes}, clusters={cfg.clusters}, "
                          f"max_classes={cfg.max_classes}); the catalog has {len(catalog.group('floor'))} floor "
                          f"assets in all")
    used: set[str] = set()
    partners = {g: _CACHE.get(catalog, ("partners", fkey, g),
                              lambda pool=pool, g=g: partner_map(pool.classes, cfg.class_pool_seed, g))
                if cfg.pairing_prob > 0 and room_type is None else {} for g, pool in pools.items()}
    template: RoomTemplate | None = None
    small_key: tuple[str, ...] | None = None
    if room_type is not None:
        template = ROOM_TEMPLATES[room_type]
        stats["room_objects"] = "template"
        if propose is not None:
            vocab = {g: tuple(sorted({canonical_class(c) for c in pools[g].classes})) for g in ("floor", "wall", "obj")}
            proposed, stats["room_llm"] = propose(room_type, vocab)
            if proposed is not None:
                template, stats["room_objects"] = proposed, "llm"
        small, obj_pool = template.small, pools["obj"]
        small_key = tuple(small)
        pools["obj"] = _CACHE.get(catalog, ("room-obj", fkey, small_key), lambda: _Pool(tuple({
            r.id: r for name in small for r in obj_pool.item_models(name, cfg.assets_per_class, cfg.class_pool_seed)
        }.values())))

    real_classes = ({c for pool in pools.values() for c in pool.classes if classes.match(c) is not None}
                    if classes is not None else set())

    def real_of(pool: _Pool, g: str, key: tuple) -> _Pool | None:
        if classes is None:
            return None

        def build() -> _Pool:
            real = _Pool(tuple(r for r in pool.records if r.class_name in real_classes))
            if pool and len(real.classes) < cfg.min_real_classes:
                if g != "fit":
                    log.info("selection: only %d %s class(es) match the %s classes (< min_real_classes = %d); "
                             "complementary draws of this group use the whole pool", len(real.classes), g,
                             classes.name, cfg.min_real_classes)
                return _Pool(())
            return real

        return _CACHE.get(catalog, ("real", classes.name, classes.classes) + key, build)

    drawers = {g: _Drawer(pool, real_of(pool, g, ("pool", fkey, g)), cfg, complementary, partners[g], used, stats)
               for g, pool in pools.items()}
    obj_sizes = _CACHE.get(catalog, ("sizes", fkey, small_key), lambda: np.array(
        [r.size for r in pools["obj"].records], dtype=np.float64).reshape(-1, 3))
    fit_drawers: dict[str, _Drawer | None] = {}
    warned: set[str] = set()

    def group_draw(g: str, n: int) -> list[AssetRecord]:
        if n <= 0:
            return []
        if not pools[g]:
            if g not in warned:
                warned.add(g)
                log.warning("selection: no %s asset to select from (%d requested per draw); none selected", g, n)
            return []
        return drawers[g].draw(n, rng)

    def on_top_draw(parent: AssetRecord, holds: bool = True) -> tuple[AssetRecord, ...]:
        if not holds or not parent.supports or cfg.on_top_count <= 0:
            return ()
        if not cfg.on_top_fit:
            return tuple(group_draw("obj", cfg.on_top_count))
        if parent.id not in fit_drawers:
            def build_fit(parent: AssetRecord = parent) -> _Pool:
                mask = fits_support_mask(parent, obj_sizes)
                return _Pool(tuple(r for r, m in zip(pools["obj"].records, mask) if m))

            sub = _CACHE.get(catalog, ("fit", fkey, small_key, parent.id, parent.supports), build_fit)
            real_sub = real_of(sub, "fit", ("fit", fkey, parent.id, parent.supports))
            fit_drawers[parent.id] = (_Drawer(sub, real_sub, cfg, complementary, partners["obj"], used, stats)
                                      if sub else None)
        drawer = fit_drawers[parent.id]
        if drawer is None:
            stats["no_fitting_on_top"] += 1
            return ()
        return tuple(drawer.draw(cfg.on_top_count, rng))

    stats["no_fitting_on_top"] = 0
    if room_type is None:
        floor = group_draw("floor", cfg.floor_count)
        wall = group_draw("wall", cfg.wall_count)
        floor_holds, wall_holds = [True] * len(floor), [True] * len(wall)
    else:
        assert template is not None
        floor, floor_holds = _template_draw(pools["floor"], template.floor, rng, used, stats, cfg)
        wall, wall_holds = _template_draw(pools["wall"], template.wall, rng, used, stats, cfg)
    floor_on_top = tuple(on_top_draw(r, h) for r, h in zip(floor, floor_holds))
    wall_on_top = tuple(on_top_draw(r, h) for r, h in zip(wall, wall_holds))
    return Selection(tuple(floor), tuple(wall), floor_on_top, wall_on_top, complementary, stats)
