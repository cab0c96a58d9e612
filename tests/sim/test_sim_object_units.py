"""Object lists: the units of ``yaw`` (radians) and ``height`` ([z_min, z_max], metres) in every error."""

import numpy as np
import pytest
import yaml

from psgsl_pgm.sim import load_objects


def _load(tmp_path, item):
    (tmp_path / "o.yaml").write_text(yaml.safe_dump({"objects": [item]}))
    return load_objects(tmp_path / "o.yaml")


@pytest.mark.parametrize("extra, message", [
    ({"height": 0.9}, r"field 'objects\[0\]\.height' must be a list of numbers, got float 0\.9 \(height: "
                      r"\[z_min, z_max\] in metres above the floor, e\.g\. \[0\.0, 0\.9\]\)"),
    ({"height": [1.0, 0.5]}, r"'objects\[0\]\.height' must have z_min < z_max, got \[1\.0, 0\.5\] \(height: "
                             r"\[z_min, z_max\] in metres above the floor"),
    ({"yaw": "90deg"}, r"'objects\[0\]\.yaw' must be a number, got str '90deg' \(yaw: the box's rotation in radians"),
    ({"yaw": 90}, r"'objects\[0\]\.yaw' is 90, beyond ±2π \(yaw: the box's rotation in radians, counter-clockwise "
                  r"from the x axis; 90° is 1\.5708 rad\)"),
    ({"size": [0.5]}, r"'objects\[0\]\.size' must have 2 entries.*\(size: \[sx, sy\] of the box in metres\)"),
])
def test_unit_in_the_error(tmp_path, extra, message):
    with pytest.raises(ValueError, match=message):
        _load(tmp_path, {"class": "oven", "position": [1.0, 2.0], **extra})


def test_yaw_in_radians_turns_the_box(tmp_path):
    (obj,) = _load(tmp_path, {"class": "oven", "position": [1.0, 2.0], "size": [0.6, 0.2], "yaw": float(np.pi / 2),
                              "height": [0.0, 0.9]})
    lo, hi = obj.footprint.min(axis=0), obj.footprint.max(axis=0)
    np.testing.assert_allclose(hi - lo, [0.2, 0.6], atol=1e-12)  # a quarter turn swaps the sides
    assert obj.z_range == (0.0, 0.9)
