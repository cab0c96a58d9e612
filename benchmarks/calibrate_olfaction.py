"""Re-make the calibration of the olfactory estimators: maximum-likelihood (D, τ, κ) and the tempering β.

    python benchmarks/calibrate_olfaction.py            # prints the fit; the defaults of ExperimentConfig are it
    python benchmarks/calibrate_olfaction.py --world-model realistic --plume-only   # the fit in another world

The tempering of both estimators is chosen for coverage on :data:`psgsl_pgm.experiment.GRID_CALIBRATION_RUNS`
(:func:`psgsl_pgm.experiment.coverage_tempering`); the AR(1) value is printed beside it.

Runs the fixed tour on :data:`psgsl_pgm.experiment.CALIBRATION_RUNS` (seeds and sources never evaluated), fits
the hit model with the wind the robot estimated from its anemometer, and prints the profile log-likelihood at
the previous hand-set values beside the fit, and the fit with the missed-hit rate δ of the hit model as a free
parameter (``fit_missed_hits=True``).
"""

import argparse
import time

from psgsl_pgm.experiment import calibrate, calibration_runs, ExperimentConfig
from psgsl_pgm.olfaction import ar1_tempering, fit_plume_parameters, hit_residuals, profile_log_likelihood, PlumeFit


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--world-model", default=None, help="make the calibration runs in this world model "
                    "(psgsl_pgm.sim.WorldModel; default: the ideal world)")
    ap.add_argument("--plume-only", action="store_true",
                    help="(D, τ, κ) and the AR(1) tempering only: no parameter grid, no coverage tempering")
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    config = ExperimentConfig(world_model=a.world_model)
    print(f"calibration runs in the {config.world_model or 'ideal'} world")
    if a.plume_only:
        data = calibration_runs(config=config)
        fit = fit_plume_parameters(data, false_hit_rate=config.false_hit_rate)
        rho, beta = ar1_tempering(hit_residuals(data, fit, false_hit_rate=config.false_hit_rate))
        print(f"readings n = {sum(len(d.hits) for d in data)}, hits {sum(int(d.hits.sum()) for d in data)}")
        print(f"D = {fit.diffusivity:.4g} m²/s, τ = {fit.lifetime:.4g} s, κ = {fit.encounter_scale:.4g} m²/s, "
              f"log L = {fit.log_likelihood:.2f}")
        print(f"residual lag-1 autocorrelation ρ = {rho:.4f} -> tempering β = (1 − ρ)/(1 + ρ) = {beta:.4f}")
        print(f"{time.perf_counter() - t0:.0f} s")
        return
    cal = calibrate(config=config)
    fit = cal.plume
    print(f"readings n = {cal.n}")
    print(f"D = {fit.diffusivity:.4g} m²/s, τ = {fit.lifetime:.4g} s, κ = {fit.encounter_scale:.4g} m²/s, "
          f"log L = {fit.log_likelihood:.2f}")
    print(f"residual lag-1 autocorrelation ρ = {cal.rho:.4f} -> tempering β = (1 − ρ)/(1 + ρ) = {cal.tempering:.4f}")
    print(f"analytic-plume score exponent λ (log score of the known sources) = {cal.pmfs_tempering:.4f}")
    for name, cov in (("Infotaxis β", cal.coverage), ("analytic-plume λ", cal.pmfs_coverage)):
        b = cov.thresholds.reshape(-1, 4)
        print(f"{name} for coverage 0.90 of the 90 % region on GRID_CALIBRATION_RUNS = {cov.tempering:.4f} (bootstrap over runs "
              f"5–95 %: {cov.interval[0]:.3f}–{cov.interval[1]:.3f}); coverage at ¼ ½ ¾ end "
              f"{[round(float(v), 3) for v in (b > cov.tempering).mean(axis=0)]}")
    data = calibration_runs(config=config)
    joint = fit_plume_parameters(data, false_hit_rate=config.false_hit_rate, fit_missed_hits=True)
    print(f"with the missed-hit rate fitted too: δ = {joint.missed_hit_rate:.4g}, D = {joint.diffusivity:.4g} m²/s, "
          f"τ = {joint.lifetime:.4g} s, κ = {joint.encounter_scale:.4g} m²/s, log L = {joint.log_likelihood:.2f}")
    for d, tau in ((0.03, 30.0), (0.01, 300.0)):
        kappa, ll = profile_log_likelihood(data, d, tau, false_hit_rate=config.false_hit_rate)
        rho, _ = ar1_tempering(hit_residuals(data, PlumeFit(d, tau, kappa, ll), false_hit_rate=config.false_hit_rate))
        print(f"  (D, τ) = ({d}, {tau}): κ̂ = {kappa:.4g}, log L = {ll:.2f}, residual ρ = {rho:.3f}")
    print(f"{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
