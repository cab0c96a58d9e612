"""The embedded message definitions: the lab's GasSensor and Anemometer field for field, and what they decode."""

from __future__ import annotations


import pytest

pytest.importorskip("rosbags", reason="the ros extra is not installed (pip install 'psgsl-pgm[ros]')")

from rosbags.typesys import get_types_from_msg

from psgsl_pgm.ros._types import (
    ANEMOMETER,
    DETECTIONS,
    GAS_SENSOR,
    _parse_definitions,
    typestore,
)

from tests.sim.house_b import shared_data  # noqa: E402

LAB = shared_data("olfaction_msgs")


@pytest.mark.parametrize("name, typ", [("GasSensor.msg", GAS_SENSOR), ("Anemometer.msg", ANEMOMETER)])
def test_embedded_definitions_match_the_labs_files(name, typ):
    path = LAB / name
    if not path.is_file():
        pytest.skip(f"the lab's message files are not here ({path})")
    lab = get_types_from_msg(path.read_text(), typ)[typ]
    ours = typestore().fielddefs[typ]
    assert [f[0] for f in ours[1]] == [f[0] for f in lab[1]]  # the same fields, in the same order
    assert ours[1] == lab[1]  # and types: the CDR layout is identical
    assert {c[0]: c[2] for c in ours[0]} == {c[0]: c[2] for c in lab[0]}  # and constants


def test_store_knows_the_robot_types():
    store = typestore()
    for typ in (GAS_SENSOR, ANEMOMETER, DETECTIONS, "tf2_msgs/msg/TFMessage", "nav_msgs/msg/OccupancyGrid",
                "geometry_msgs/msg/PoseWithCovarianceStamped"):
        assert typ in store.types
    msg = store.types[GAS_SENSOR](header=store.types["std_msgs/msg/Header"](
        stamp=store.types["builtin_interfaces/msg/Time"](sec=1, nanosec=2), frame_id="pid"), technology=51,
        manufacturer=0, mpn=0, raw=1.25, raw_units=3, raw_air=0.0, calib_a=0.0, calib_b=0.0)
    back = store.deserialize_cdr(store.serialize_cdr(msg, GAS_SENSOR), GAS_SENSOR)
    assert back.raw == 1.25 and back.header.frame_id == "pid" and back.raw_units == 3


def test_a_bags_concatenated_definitions_are_parsed():
    """MCAP storage carries a type's definition followed by ``MSG: pkg/Type`` blocks after lines of '='."""
    text = ("acme_msgs/Reading reading\nfloat64 quality\n"
            "================================================================================\n"
            "MSG: acme_msgs/Reading\nfloat64 ppm\nstring unit\n")
    types = _parse_definitions(text, "acme_msgs/msg/Smell")
    assert set(types) == {"acme_msgs/msg/Smell", "acme_msgs/msg/Reading"}
    assert [f[0] for f in types["acme_msgs/msg/Reading"][1]] == ["ppm", "unit"]
