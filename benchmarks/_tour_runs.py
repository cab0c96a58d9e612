"""What the calibration scripts share: their run options and the start of a fixed-tour run.

``calibration_check.py`` and ``calibration_record.py`` each drive the exploration tour for every (estimator,
source, seed) with the experiment's own per-step code (:class:`psgsl_pgm.experiment.VariantPosteriors`);
this module is the one place for the options that name those runs and for the lines that open one.
"""

from psgsl_pgm.experiment import VARIANTS, VariantPosteriors
from psgsl_pgm.experiment._step import start_run
from psgsl_pgm.experiment._tour import exploration_tour

__all__ = ["add_run_arguments", "start_tour_run"]


def _sources(text):
    return text.split(";")  # a source is a name or "x,y"


def _estimators(text):
    return text.split(",")


def add_run_arguments(ap, *, first_seed: int, seeds: int):
    """Add ``--first-seed``, ``--seeds``, ``--sources`` (";"-separated, parsed to a list), ``--estimators``
    (","-separated, parsed to a list) and ``--out`` (required) to the argparse parser ``ap``."""
    ap.add_argument("--first-seed", type=int, default=first_seed, help="the first seed of the runs")
    ap.add_argument("--seeds", type=int, default=seeds, help="how many seeds from --first-seed")
    ap.add_argument("--sources", type=_sources, default="oven;bed;5.0,6.0",
                    help='";"-separated sources: an object\'s name or "x,y" (m)')
    ap.add_argument("--estimators", type=_estimators, default="infotaxis,analytic-plume", help='","-separated estimators')
    ap.add_argument("--out", required=True)


def start_tour_run(source, seed, estimator, config, *, variants=VARIANTS):
    """The checked config, world, exploration tour, :class:`VariantPosteriors` (of ``variants``) and true source
    cell (row, col) of one fixed-tour run, as :func:`psgsl_pgm.experiment.run_search` starts one (but the whole
    tour, whatever ``config.stops``)."""
    config, spec, setting, world = start_run(source, seed, estimator, config)
    house = world.house
    tour = exploration_tour(house, start=setting.start_for(house))
    beliefs = VariantPosteriors(world, estimator, config, setting=setting, variants=variants)
    return config, world, tour, beliefs, house.grid.cell_of(world.source)
