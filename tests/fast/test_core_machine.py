"""What a benchmark figure ran on: the CPU's name, its usable cores and memory (assist3d.core.machine)."""

from __future__ import annotations

import json
import os

from assist3d.core.machine import cpu_model, describe_machine, usable_cores


def test_cpu_model_reads_the_first_model_name_and_falls_back_without_cpuinfo(tmp_path):
    info = tmp_path / "cpuinfo"
    info.write_text("processor\t: 0\nvendor_id\t: AuthenticAMD\nmodel name\t: AMD  EPYC 7B13\n\n"
                    "processor\t: 1\nmodel name\t: something else\n")
    assert cpu_model(info) == "AMD EPYC 7B13"  # first entry, inner spaces collapsed
    info.write_text("processor\t: 0\nmodel name\t:   \n")  # empty name: not taken
    assert cpu_model(info) not in ("", "   ")
    assert cpu_model(tmp_path / "missing") == cpu_model(info)  # the platform's answer in both cases


def test_describe_machine_is_json_and_counts_the_cores_this_process_may_use():
    m = json.loads(json.dumps(describe_machine()))
    assert set(m) == {"cpu", "cores", "memory_gib", "os", "python"}
    assert m["cores"] == usable_cores() >= 1
    if hasattr(os, "sched_getaffinity"):
        assert m["cores"] == len(os.sched_getaffinity(0))
    assert m["memory_gib"] is None or m["memory_gib"] > 0
