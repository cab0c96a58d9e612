"""The experiment's figures refuse input they cannot draw."""

import pytest


def test_the_error_chart_refuses_no_runs():
    pytest.importorskip("matplotlib")
    from psgsl_pgm.experiment import plot_error_chart

    with pytest.raises(ValueError, match="at least one run"):
        plot_error_chart([])
