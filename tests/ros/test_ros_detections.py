"""Detection boxes in the map frame: a box's yaw is its own orientation composed with its frame's yaw."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

pytest.importorskip("rosbags", reason="the ros extra is not installed (pip install 'psgsl-pgm[ros]')")

from psgsl_pgm.ros import read_bag, write_bag
from tests.ros.bags import rewrite, synthetic_episode

ROBOT_YAW, BOX_YAW = 0.5, 0.3


def test_box_yaw_is_composed_with_its_frames_yaw(tmp_path):
    ep = synthetic_episode()
    ep.pose[:, 2] = ROBOT_YAW  # the robot (and its camera, base_link) turned by 0.5 rad
    bag = write_bag(tmp_path / "bag", ep, storage="mcap")
    q = {"z": float(np.sin(BOX_YAW / 2)), "w": float(np.cos(BOX_YAW / 2))}

    def turn(topic, t, msg):  # every box turned by 0.3 rad in base_link
        if topic != "/detections":
            return msg
        dets = []
        for d in msg.detections:
            centre = dataclasses.replace(d.bbox.center, orientation=dataclasses.replace(d.bbox.center.orientation, **q))
            dets.append(dataclasses.replace(d, bbox=dataclasses.replace(d.bbox, center=centre)))
        return dataclasses.replace(msg, detections=dets)

    data = read_bag(rewrite(bag, tmp_path / "turned", change=turn))
    assert len(data.detections) == 4
    for d, cells in zip(data.detections, ep.frame_cells):
        np.testing.assert_allclose(d.camera[2], ROBOT_YAW, rtol=0, atol=1e-12)
        np.testing.assert_allclose(d.yaw, ROBOT_YAW + BOX_YAW, rtol=0, atol=1e-12)
        np.testing.assert_allclose(d.centre, ep.grid.cell_to_world(cells), rtol=0, atol=1e-9)  # the cell's centre
