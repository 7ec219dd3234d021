"""Seeding helpers: every random choice takes an explicit ``numpy.random.Generator``."""

from __future__ import annotations

import hashlib

import numpy as np


def scene_seed(base_seed: int, index: int) -> int:
    """The integer seed of scene ``index`` of a dataset generated with ``base_seed``.

    Derived with ``SeedSequence`` so any scene can be regenerated alone.
    """
    ss = np.random.SeedSequence([int(base_seed) & 0xFFFFFFFF, int(index)])
    return int(ss.generate_state(1, dtype=np.uint32)[0])


def make_rng(seed: int, *keys: int | str) -> np.random.Generator:
    """A generator for ``seed`` and an optional stream key (e.g. a stage name).

    Distinct keys give independent streams, so adding random draws to one stage never changes
    another stage's output.
    """
    entropy = [int(seed) & 0xFFFFFFFF]
    for k in keys:
        if isinstance(k, str):
            entropy.append(int.from_bytes(hashlib.blake2b(k.encode(), digest_size=4).digest(), "little"))
        else:
            entropy.append(int(k) & 0xFFFFFFFF)
    return np.random.default_rng(np.random.SeedSequence(entropy))


def stable_hash(text: str, digits: int = 16) -> str:
    """A short, platform-independent hex digest of ``text``."""
    return hashlib.blake2b(text.encode("utf-8"), digest_size=max(1, digits // 2)).hexdigest()
