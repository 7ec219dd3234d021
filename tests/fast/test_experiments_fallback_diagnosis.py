"""experiments/tools/fallback_diagnosis.py: the per-object categories behind the "Fallback proposals" figures of
experiments/fidelity-log.md."""

from __future__ import annotations

import numpy as np


def test_classify_names_what_happened_to_each_object(load_script):
    fd = load_script("fallback_diagnosis")
    n = 1000
    obj = np.zeros(n, bool)
    obj[:200] = True

    def kind(*ranges):
        m = np.zeros((len(ranges), n), bool)
        for row, (a, b) in enumerate(ranges):
            m[row, a:b] = True
        return fd.classify(m, obj)

    assert kind((0, 190)) == ("matched", True)
    assert kind((0, 80)) == ("partial", False)  # all on the object, 40 % of it
    assert kind((0, 80), (80, 170)) == ("partial", True)  # two fragments that together would match
    assert kind((0, 200), (0, 180))[0] == "matched"
    assert kind((0, 600))[0] == "merged"  # the object and 400 points of something else: IoU 0.33
    assert kind((0, 150), (150, 200))[0] == "matched"  # best IoU 0.75
    assert kind((100, 1000)) == ("inside-others", False)  # half of it in a 900-point mask: IoU 0.1
    assert kind((150, 1000)) == ("uncovered", False)  # a quarter of it in such a mask
    assert kind((900, 1000)) == ("uncovered", False)
    assert fd.classify(np.zeros((0, n), bool), obj) == ("uncovered", False)
