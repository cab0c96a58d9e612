"""Strict JSON of the result files: every non-finite float becomes null, nothing else changes."""

import json
import math

import numpy as np

from psgsl_pgm.io._json import json_safe


def test_non_finite_numbers_become_none_at_any_depth():
    obj = {"rmst": {"value": 12.5, "ci95": (float("nan"), 20.0)}, "median": np.float64("inf"),
           "runs": [{"error": -math.inf, "n": 3}], "label": "nan", "found": True, "seeds": [0, 1]}
    out = json_safe(obj)
    assert out == {"rmst": {"value": 12.5, "ci95": [None, 20.0]}, "median": None,
                   "runs": [{"error": None, "n": 3}], "label": "nan", "found": True, "seeds": [0, 1]}
    json.dumps(out, allow_nan=False)  # strict JSON: would raise on a NaN left behind
    assert math.isnan(obj["rmst"]["ci95"][0])  # a copy: the input is left as it was


def test_finite_values_keep_their_type_and_value():
    out = json_safe([np.float64(0.1), 1e308, -0.0, 7, None])
    assert out == [0.1, 1e308, -0.0, 7, None] and type(out[0]) is np.float64 and type(out[3]) is int
