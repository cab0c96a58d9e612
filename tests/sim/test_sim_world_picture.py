"""`world check --png`: room names readable on open floor, no label over another, wind arrows with a scale."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import yaml  # noqa: E402

from psgsl_pgm import load_world  # noqa: E402
from psgsl_pgm.cli._world import plot_world  # noqa: E402
from psgsl_pgm.sim import potential_flow, save_ros_map  # noqa: E402
from psgsl_pgm.sim._plot import declutter  # noqa: E402

from .test_sim_worldfile import world_dict, write_house  # noqa: E402


@pytest.fixture
def figure(tmp_path):
    grid, _ = write_house(tmp_path)
    # the map draws a table in the middle of the kitchen (occupied cells inside the room's mask)
    c = grid.cell_centres()
    table = (c[..., 0] > 0.8) & (c[..., 0] < 2.2) & (c[..., 1] > 1.3) & (c[..., 1] < 2.7)
    save_ros_map(grid.with_occupancy(grid.occupancy | table), tmp_path / "map.yaml")
    # two names for one place (the oven's centre), and a third source elsewhere
    (tmp_path / "w.yaml").write_text(yaml.safe_dump(world_dict(sources={"oven": "oven", "B": [1.0, 0.6],
                                                                        "S1": [4.0, 1.0]}, start=[4.5, 2.0])))
    spec = load_world(tmp_path / "w.yaml")
    fig = plot_world(spec)
    fig.canvas.draw()
    yield spec, fig
    plt.close(fig)


def test_no_label_covers_another(figure):
    spec, fig = figure
    ax = fig.axes[0]
    r = fig.canvas.get_renderer()
    texts = [t for t in ax.texts if t.get_visible() and t.get_text()]
    boxes = [t.get_window_extent(r) for t in texts]
    for i in range(len(boxes)):
        for j in range(i):
            assert not boxes[i].overlaps(boxes[j]), (texts[i].get_text(), texts[j].get_text())
    names = sorted(t.get_text() for t in texts)
    assert "B, oven" in names and "S1" in names  # one label per place (YAML sorts the names)
    assert {"Kitchen", "LivingRoom", "oven"} <= set(names)


def test_room_names_sit_on_open_floor_on_a_backing(figure):
    spec, fig = figure
    house = spec.house()
    ax = fig.axes[0]
    for t in ax.texts:
        if t.get_text() in house.room_names:
            r, c = house.grid.world_to_cell(np.array(t.get_position()))
            assert house.grid.free[r, c] and not house.furniture[r, c], t.get_text()
            assert house.room_names[house.room_labels[r, c]] == t.get_text()
            box = t.get_bbox_patch()
            assert box is not None and box.get_facecolor()[:3] == (1.0, 1.0, 1.0)


def test_wind_arrows_have_a_stated_scale(figure):
    spec, fig = figure
    ax = fig.axes[0]
    (q,) = [c for c in ax.collections if type(c).__name__ == "Quiver"]
    keys = [a for a in ax.get_children() if type(a).__name__ == "QuiverKey"]
    assert len(keys) == 1
    key = keys[0]
    assert key.label == f"wind {key.U:g} m/s" and key.U > 0
    # the 95th-percentile speed spans 90 % of the arrow spacing (scale in m/s per metre of arrow)
    house = spec.house()
    stride = max(2, min(house.shape) // 25)
    v = potential_flow(house.grid, house.inlet, house.outlet, mean_speed=spec.wind["speed"]).velocity
    speed = np.hypot(v[..., 0], v[..., 1])[::stride, ::stride][house.grid.free[::stride, ::stride]]
    assert q.scale == pytest.approx(np.percentile(speed, 95) / (0.9 * stride * house.grid.resolution), rel=1e-12)
    assert key.U <= np.percentile(speed, 95) < 5 * key.U  # a round number of the arrows' own size


def test_declutter_moves_a_label_off_another_and_off_a_marker():
    fig, ax = plt.subplots(figsize=(3, 3))
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    a = ax.text(0.5, 0.5, "first", ha="center", va="center")
    b = ax.text(0.5, 0.5, "second", ha="center", va="center")
    c = ax.text(0.2, 0.2, "third", ha="center", va="center")
    assert declutter(ax, [a, b, c], avoid=[(0.2, 0.2)]) == 0
    r = fig.canvas.get_renderer()
    assert a.get_position() == pytest.approx((0.5, 0.5), abs=1e-12)  # the first keeps its place
    assert not a.get_window_extent(r).overlaps(b.get_window_extent(r))
    assert c.get_position() != (0.2, 0.2)
    plt.close(fig)
