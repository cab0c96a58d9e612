"""The score exponent λ of PMFS as published (:class:`psgsl_pgm.olfaction.FilamentPMFS`, estimator ``pmfs``).

    python benchmarks/calibrate_pmfs.py            # prints λ; ExperimentConfig.filament_pmfs_tempering is it

PMFS's posterior p(s | g) ∝ p(s) Π_c [1 − conf_c γ |ĥ_c − h_c(s)|] is a pseudo-likelihood whose sharpness grows
with the number of compared cells. As for the analytic-plume estimator, λ in p(s) (Π_c […])^λ is chosen to
maximise the log posterior of the known source at ¼, ½, ¾ and the end of each calibration run
(:func:`psgsl_pgm.olfaction.score_tempering`: a proper scoring rule), on the fixed tour of
:data:`psgsl_pgm.experiment.CALIBRATION_RUNS` (seeds and sources never evaluated), with the robot's calibrated
diffusivity and a uniform prior over the free cells.
"""

import argparse
import time

import numpy as np

from psgsl_pgm.experiment import CALIBRATION_RUNS, ExperimentConfig, calibration_runs
from psgsl_pgm.olfaction import FilamentPMFS, PlumeModel, score_tempering


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--world-model", default=None, help="make the calibration runs in this world model")
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    config = ExperimentConfig(world_model=a.world_model)
    data = calibration_runs(CALIBRATION_RUNS, config=config)
    print(f"{len(data)} calibration runs, {sum(len(d.hits) for d in data)} readings ({time.perf_counter() - t0:.0f} s)")
    scores, priors, truth = [], [], []
    for k, run in enumerate(data):
        geo = run.model.geometry
        model = PlumeModel.from_grid_map(geo, None, outlets=run.model.outlets, diffusivity=config.diffusivity,
                                         lifetime=config.lifetime, encounter_scale=config.encounter_scale)
        est = FilamentPMFS(model, seed=k)
        r, c = model.cell_of(run.source)
        n = len(run.hits)
        keep = {int(round(f * n)) for f in (0.25, 0.5, 0.75, 1.0)}
        for j in range(n):
            est.update(run.positions[j], bool(run.hits[j]), None if run.winds is None else run.winds[j])
            if j + 1 in keep:
                lp = est._log_prior
                with np.errstate(invalid="ignore"):  # −inf − (−inf) off the support, replaced by 0
                    score = np.where(np.isfinite(lp), est.log_posterior.ravel() - lp, 0.0)  # S(s) + const
                scores.append(score)
                priors.append(lp)
                truth.append(r * model.shape[1] + c)
        err = np.hypot(*(np.array(est.expected_position()) - run.source))
        print(f"run {k}: {run.source} error of E[s] {err:.2f} m "
              f"({time.perf_counter() - t0:.0f} s)")
    lam = score_tempering(scores, priors, truth)
    print(f"PMFS score exponent λ (log score of the known sources) = {lam:.4f}")
    for value in (1.0, lam):
        ll = []
        for sc, lp, t in zip(scores, priors, truth):
            z = lp + value * sc
            ll.append(z[t] - np.logaddexp.reduce(z[np.isfinite(z)]))
        print(f"  λ = {value:.4f}: mean log p(true cell) = {np.mean(ll):.3f}")
    print(f"{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
