"""The closed loop with the PMFS estimator: φ_G is the information its own update takes in, so repeated misses at
one stop stop paying and the robot moves on (no two-stop limit cycle)."""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.special import entr

from psgsl_pgm import GridMap
from psgsl_pgm.olfaction import PMFSEstimator
from psgsl_pgm.search import DetectionModel, FreeSpace, Situation, choose
from psgsl_pgm.search._policies import olfactory_gain, space_aware_gain
from psgsl_pgm.sim import Camera

RES = 0.25


class _AsIfBayesian(PMFSEstimator):
    """PMFS whose update the policy takes for a Bayes update (φ_G = I(S; hit)): how the loop chose before."""

    reading_log_ratio = None


@pytest.fixture(scope="module")
def corridor():
    """A 2-m room and, from its south-west corner, a 1-m wide corridor east to a dead end 9.75 m away; a weak
    wind along +x, into the dead end."""
    occ = np.ones((18, 40), bool)
    occ[1:5, 1:-1] = False  # the corridor, one lattice row (y = 0.875 m) drivable
    occ[1:-1, 1:10] = False  # the room
    grid = GridMap(occ, RES)
    space = FreeSpace(SimpleNamespace(grid=grid, robot_obstacles=occ), Camera(), clearance=0.25)
    wind = np.zeros(occ.shape + (2,))
    wind[..., 0] = 0.2
    return grid, space, wind


def _situation(est, space, cell, cache, grid):
    return Situation(est.posterior, SimpleNamespace(estimator=est), "olfaction", space, cell, 0.0, 0.25, 1.0, 1.0,
                     2.0, 0.5, cache, "per-time", DetectionModel(grid, 0.5), 1.0)


def _after_repeated_misses(cls, corridor, n_misses=40):
    """A hit at the dead end's stop A, then ``n_misses`` misses at A and its neighbour B in turn, each stop "not
    found" — the readings of a robot shuttling between them; it stands at B. Returns (estimator, A, B)."""
    grid, space, wind = corridor
    est = cls.from_grid_map(grid, wind, tempering=0.38, diffusivity=0.02, boundary="open")
    detection = DetectionModel(grid, 0.5)
    a, b = space.snap((9.375, 0.875)), space.snap((8.875, 0.875))
    est.update(space.position(a), True)
    for m in range(n_misses):
        c = (a, b)[m % 2]
        est.condition(detection.not_found_log_likelihood(space.position(c)[None]))
        est.update(space.position(c), False)
    return est, a, b


def test_repeated_misses_drive_the_policy_away_from_a_stop(corridor):
    """After 40 misses at the two stops at the dead end, PMFS's entropy has hardly moved — the readings do not
    accumulate — yet I(S; hit at A) under its posterior is what it was: taken for Bayes updates, the misses keep
    promising information at A and the robot at B goes back (the two-stop limit cycle). φ_G under PMFS's own
    update sees that one more miss there teaches nothing, and the robot leaves both stops. (Space-aware infotaxis
    takes the same outcome posteriors; :func:`test_phi_g_is_the_expected_entropy_drop_of_the_pmfs_update` checks
    them against the estimator's update.)"""
    grid, space, _ = corridor
    bayes, a, b = _after_repeated_misses(_AsIfBayesian, corridor)
    est, _, _ = _after_repeated_misses(PMFSEstimator, corridor)
    np.testing.assert_array_equal(est.posterior, bayes.posterior)  # the same beliefs; only the policy differs
    sit = _situation(est, space, b, {}, grid)
    phi_bayes = olfactory_gain(_situation(bayes, space, b, {}, grid), np.array([a]))[0]
    phi_own = olfactory_gain(sit, np.array([a]))[0]
    assert phi_bayes > 0.1 and abs(phi_own) < 0.02 * phi_bayes
    early, _, _ = _after_repeated_misses(PMFSEstimator, corridor, n_misses=10)
    assert abs(early.entropy() - est.entropy()) < phi_bayes / 3  # 30 misses took in less than one was promised
    assert choose("infotaxis", _situation(bayes, space, b, {}, grid)).cell == a  # the cycle this guards against
    assert choose("infotaxis", sit).cell not in (a, b)


def test_phi_g_is_the_expected_entropy_drop_of_the_pmfs_update(corridor):
    """φ_G against brute force: each outcome applied with :meth:`update` to a replayed estimator, its entropy
    weighted by the predictive P(hit) = Σ p(s) h_x(s); and the space-aware outcome posteriors the same way."""
    grid, space, wind = corridor
    hist = [((1.1, 1.6), False), ((1.6, 1.6), True), ((1.6, 1.6), False), ((4.1, 0.9), False)]
    detection = DetectionModel(grid, 0.5)

    def replay():
        e = PMFSEstimator.from_grid_map(grid, wind, tempering=0.38, diffusivity=0.02, boundary="open")
        for x, g in hist:
            e.condition(detection.not_found_log_likelihood(np.array([x])))
            e.update(x, g)
        return e

    est = replay()
    cell = space.snap((4.1, 0.9))
    sit = _situation(est, space, cell, {}, grid)
    cells = np.array([space.snap(xy) for xy in ((1.6, 1.6), (4.6, 0.9), (7.6, 0.9), (1.1, 2.6))])
    phi = olfactory_gain(sit, cells)
    post = est.posterior.ravel()
    h_now = float(entr(post).sum())
    for k, c in enumerate(cells):
        x = space.position(c)
        p_hit = float(est.hit_probability(x[None]).ravel() @ post)
        expect = h_now
        for g, prob in ((False, 1 - p_hit), (True, p_hit)):
            after = replay()
            after.update(x, g)
            expect -= prob * after.entropy()
        np.testing.assert_allclose(phi[k], expect, rtol=1e-10, atol=1e-13)
    assert abs(phi[0]) < 0.2 * phi[1:].max()  # the revisited stop promises little
    # space-aware: V_now − (1 − P_f) Σ_h P(h | p, F̄) V(D_h, H_h), the outcome posteriors by update()
    got = space_aware_gain(sit, cells)
    ell, disc_bits = 1.0, np.log2(np.pi * 0.25 / RES**2)

    def value(d, h_bits):
        return np.log2(1.0 + d / ell + 2.0 ** (max(h_bits - disc_bits, 0.0) - 1.0) - 0.5)

    def past(d):  # the distance past the found radius r = 0.5 m, 0 where unreachable
        return np.where(np.isfinite(d), np.maximum(d - 0.5, 0.0), 0.0)

    v_now = value(float(post @ past(space.distances(cell))), h_now / np.log(2))
    for k, c in enumerate(cells):
        x = space.position(c)
        w = np.exp(detection.not_found_log_likelihood(x[None]).ravel())
        u = post * w
        p_f = 1 - u.sum()
        lik = est.hit_probability(x[None]).ravel()
        d = past(space.distances(c))
        total = 0.0
        for g, prob in ((False, (u @ (1 - lik)) / u.sum()), (True, (u @ lik) / u.sum())):
            after = replay()
            after.condition(detection.not_found_log_likelihood(x[None]))
            after.update(x, g)
            q = after.posterior.ravel()
            total += prob * value(float(q @ d), after.entropy() / np.log(2))
        np.testing.assert_allclose(got[k], v_now - (1 - p_f) * total, rtol=1e-9, atol=1e-12)
