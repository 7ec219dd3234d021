"""The machine a measurement ran on, for the figures of ``assist3d bench`` and ``bench-train``.

The same code runs at very different speeds on different CPUs: a segmenter training step is 1.65x the
float32 baseline on a Xeon that multiplies bfloat16 in hardware and 1.18x on an AMD EPYC that does not
(docs/throughput.md). A speed figure without its machine cannot be compared, so the benchmarks' JSON
carry :func:`describe_machine` under the key ``machine``.
"""

from __future__ import annotations

import os
import platform
from pathlib import Path

from .bounds import machine_memory_bytes

__all__ = ["cpu_model", "usable_cores", "describe_machine"]

CPUINFO = Path("/proc/cpuinfo")


def cpu_model(cpuinfo: Path = CPUINFO) -> str:
    """The CPU's model name (Linux: the first ``model name`` of ``cpuinfo``), else what :mod:`platform`
    knows (the processor or the architecture), else ``"unknown"``."""
    try:
        with open(cpuinfo, encoding="utf-8", errors="replace") as f:
            for line in f:
                key, sep, value = line.partition(":")
                if sep and key.strip() == "model name" and value.strip():
                    return " ".join(value.split())
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown"


def usable_cores() -> int:
    """Cores this process may run on (its CPU affinity where the OS has one, else all)."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


def describe_machine() -> dict:
    """``{"cpu", "cores", "memory_gib", "os", "python"}``: what a benchmark figure ran on (``memory_gib`` is
    the physical memory or the cgroup limit if smaller, None if unknown)."""
    mem = machine_memory_bytes()
    return {"cpu": cpu_model(), "cores": usable_cores(), "memory_gib": round(mem / 2**30, 1) if mem else None,
            "os": f"{platform.system()} {platform.release()}".strip(), "python": platform.python_version()}
