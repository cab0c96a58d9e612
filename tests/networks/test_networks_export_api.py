"""psgsl_pgm.networks.export and ``psgsl export-networks``: the committed files of networks/, regenerated."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from psgsl_pgm.cli._main import main
from psgsl_pgm.networks import CANONICAL, canonical_network, draw_network, export, network_evidence

NETWORKS_DIR = Path(__file__).resolve().parents[2] / "networks"
TEXT_FORMATS = ("xmlbif", "bif")


def test_export_writes_exactly_the_committed_text_files(tmp_path):
    written = export(tmp_path / "new" / "dir", drawings=False)  # parents are created
    assert [p.name for p in written] == [f"{n}.{f}" for n in CANONICAL for f in TEXT_FORMATS]
    for path in written:
        assert path.read_bytes() == (NETWORKS_DIR / path.name).read_bytes(), f"{path.name} differs"
    assert not list((tmp_path / "new" / "dir").glob(".*.tmp"))  # no temporary file left behind


def test_export_draws_one_png_per_network(tmp_path):
    from PIL import Image

    written = export(tmp_path)
    pngs = [p for p in written if p.suffix == ".png"]
    assert [p.stem for p in pngs] == list(CANONICAL)
    for path in pngs:
        with Image.open(path) as im:
            assert im.format == "PNG" and im.size[0] >= 700 and im.size[1] >= 400


def test_export_refuses_a_file_as_directory(tmp_path):
    target = tmp_path / "file"
    target.write_text("x")
    with pytest.raises(ValueError, match="directory must be a directory"):
        export(target)


def test_cli_export_networks_prints_every_path(tmp_path, capsys):
    assert main(["export-networks", str(tmp_path), "--no-drawings"]) == 0
    lines = capsys.readouterr().out.split()
    assert [Path(x).name for x in lines] == [f"{n}.{f}" for n in CANONICAL for f in TEXT_FORMATS]
    assert all(Path(x).parent == tmp_path for x in lines)


@pytest.mark.parametrize("name", sorted(CANONICAL))
def test_drawing_marks_observed_nodes_and_has_a_legend(name):
    import matplotlib.pyplot as plt

    _, model = canonical_network(name)
    ax = draw_network(model)
    nodes = [c for c in ax.collections if len(c.get_offsets()) == model.number_of_nodes()]
    assert len(nodes) == 1
    widths = np.asarray(nodes[0].get_linewidths())
    observed = set(network_evidence(model))
    expected = np.array([2.5 if v in observed else 0.8 for v in model.nodes()])
    np.testing.assert_array_equal(widths, expected)
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "thick border: observed (evidence)" in legend
    plt.close(ax.figure)
