"""Re-make the calibration of the olfactory estimators: maximum-likelihood (D, τ, κ) and the tempering β.

    python benchmarks/calibrate_olfaction.py            # prints the fit; the defaults of ExperimentConfig are it

Runs the fixed tour on :data:`psgsl_pgm.experiment.CALIBRATION_RUNS` (seeds and sources never evaluated), fits
the hit model with the wind the robot estimated from its anemometer, and prints the profile log-likelihood at
the previous hand-set values beside the fit.
"""

import time

from psgsl_pgm.experiment import calibrate, calibration_runs, ExperimentConfig
from psgsl_pgm.olfaction import ar1_tempering, hit_residuals, profile_log_likelihood, PlumeFit


def main():
    t0 = time.perf_counter()
    config = ExperimentConfig()
    cal = calibrate(config=config)
    fit = cal.plume
    print(f"readings n = {cal.n}")
    print(f"D = {fit.diffusivity:.4g} m²/s, τ = {fit.lifetime:.4g} s, κ = {fit.encounter_scale:.4g} m²/s, "
          f"log L = {fit.log_likelihood:.2f}")
    print(f"residual lag-1 autocorrelation ρ = {cal.rho:.4f} -> tempering β = (1 − ρ)/(1 + ρ) = {cal.tempering:.4f}")
    print(f"PMFS score exponent λ (log score of the known sources) = {cal.pmfs_tempering:.4f}")
    data = calibration_runs(config=config)
    for d, tau in ((0.03, 30.0), (0.01, 300.0)):
        kappa, ll = profile_log_likelihood(data, d, tau, false_hit_rate=config.false_hit_rate)
        rho, _ = ar1_tempering(hit_residuals(data, PlumeFit(d, tau, kappa, ll), false_hit_rate=config.false_hit_rate))
        print(f"  (D, τ) = ({d}, {tau}): κ̂ = {kappa:.4g}, log L = {ll:.2f}, residual ρ = {rho:.3f}")
    print(f"{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
