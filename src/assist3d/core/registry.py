"""One way to plug in an implementation: a named registry per extension point.

Dataset readers (:data:`assist3d.data.READERS`), ray casters (:data:`assist3d.render.raycast.CASTERS`)
and relation planners (:data:`assist3d.planning.planners.PLANNERS`) are each a :class:`Registry`:
a name maps to a factory, registered with the decorator where the implementation lives::

    from assist3d.render.raycast import CASTERS

    @CASTERS.register("optix")
    def _optix(vertices, faces):
        return OptixCaster(vertices, faces)

An unknown name is refused with the closest registered one (``"unknown ray caster 'embre'; did
you mean 'embree'?"``), raised as the error class of the extension point.
"""

from __future__ import annotations

import difflib
from typing import Callable, Generic, Iterator, TypeVar

from .errors import AssistError, ConfigError

T = TypeVar("T")


class Registry(Generic[T]):
    """Named entries of one kind (``kind`` names it in messages; ``error`` is raised for unknown names)."""

    def __init__(self, kind: str, *, error: type[AssistError] = ConfigError) -> None:
        self.kind = kind
        self.error = error
        self._entries: dict[str, T] = {}

    def register(self, name: str) -> Callable[[T], T]:
        """Decorator: ``@REGISTRY.register("name")`` over a factory (or any value) adds it under ``name``."""
        def add(entry: T) -> T:
            self.add(name, entry)
            return entry

        return add

    def add(self, name: str, entry: T) -> None:
        """Add ``entry`` under ``name``; a name is registered once (a second one is a programming error)."""
        if not name or name != name.strip():
            raise ValueError(f"{self.kind} name {name!r}: expected a non-empty name without surrounding spaces")
        if name in self._entries:
            raise ValueError(f"{self.kind} {name!r} is already registered")
        self._entries[name] = entry

    def remove(self, name: str) -> None:
        """Take ``name`` out (a plugin unloading itself, a test cleaning up); unknown names are ignored."""
        self._entries.pop(name, None)

    def closest(self, name: str) -> str | None:
        """The registered name closest to ``name`` (a likely typo), if any is close."""
        close = difflib.get_close_matches(name, list(self._entries), n=1)
        return close[0] if close else None

    def hint(self, name: str) -> str:
        """``"; did you mean 'x'?"`` or ``"; choose one of a, b, c"`` for an unknown ``name``."""
        close = self.closest(name)
        return f"; did you mean {close!r}?" if close else f"; choose one of {', '.join(self._entries)}"

    def get(self, name: str) -> T:
        """The entry registered as ``name``; ``self.error`` naming the closest one otherwise."""
        try:
            return self._entries[name]
        except (KeyError, TypeError):
            raise self.error(f"unknown {self.kind} {name!r}{self.hint(str(name))}") from None

    def names(self) -> tuple[str, ...]:
        """The registered names, in registration order."""
        return tuple(self._entries)

    def __contains__(self, name: object) -> bool:
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}: {', '.join(self._entries)})"
