"""Error texts: cells as plain (row, col), no numpy reprs, no "over all cells … along its last axis"."""

import numpy as np

from psgsl_pgm.cli._main import main


def _estimate(tmp_path, class_probs, olfactory):
    (tmp_path / "o.yaml").write_text("Gases:\n  - gas: smoke\n    probs: {oven: 0.6, microwave: 0.3, other: 0.1}\n")
    np.save(tmp_path / "c.npy", class_probs)
    np.save(tmp_path / "g.npy", olfactory)
    return main(["estimate", "--ontology", str(tmp_path / "o.yaml"), "--class-probs", str(tmp_path / "c.npy"),
                 "--olfactory", str(tmp_path / "g.npy"), "--out", str(tmp_path / "s.npy")])


def test_a_bad_cell_is_named_by_row_and_column_without_numpy_reprs(tmp_path, capsys):
    p = np.full((4, 5, 3), 1 / 3)
    p[2, 3] = 0.5
    assert _estimate(tmp_path, p, np.full((4, 5), 1 / 20)) == 2
    err = capsys.readouterr().err
    assert "must sum to 1 along its last axis (tolerance 1e-06), got a sum of 1.5 at cell (2, 3) (row, col)" in err
    assert "np." not in err and "int64" not in err


def test_a_total_over_all_cells_does_not_claim_an_axis(tmp_path, capsys):
    assert _estimate(tmp_path, np.full((4, 5, 3), 1 / 3), np.full((4, 5), 1 / 10)) == 2
    err = capsys.readouterr().err
    assert "--olfactory (p(s | g)) must sum to 1 over all cells (tolerance 1e-06), got a sum of 2.0" in err
    assert "axis" not in err
