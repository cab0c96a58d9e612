"""The grid plume model: discretisation properties, adjoint consistency and the Vergassola K0 solution."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import k0

from psgsl_pgm import GridMap
from psgsl_pgm.olfaction import (
    PlumeModel,
    advection_diffusion_operator,
    bernoulli,
    correlation_length,
    vergassola_concentration,
    vergassola_encounter_rate,
    vergassola_encounter_scale,
)


def _random_map(rng, shape=(9, 11), p_wall=0.2):
    occ = rng.random(shape) < p_wall
    occ[shape[0] // 2, shape[1] // 2] = False
    wind = rng.normal(scale=0.3, size=shape + (2,))
    outlets = (rng.random(shape) < 0.05) & ~occ
    return occ, wind, outlets


# --- Bernoulli function and operator ----------------------------------------------------------------------------
def test_bernoulli_identity_and_limits():
    x = np.concatenate([np.linspace(-50, 50, 2001), [0.0, 1e-3, -1e-3, 1e-3 - 1e-12, 1e-3 + 1e-12, 800.0, -800.0]])
    b = bernoulli(x)
    assert np.all(b[np.abs(x) < 700] > 0)
    np.testing.assert_allclose(bernoulli(-x) - b, x, rtol=1e-12, atol=1e-12)  # B(−x) − B(x) = x
    np.testing.assert_allclose(bernoulli([0.0]), [1.0], rtol=0, atol=0)
    # the series branch agrees with the closed form where they meet
    np.testing.assert_allclose(bernoulli([0.999e-3, 1.001e-3]), [0.999e-3, 1.001e-3] / np.expm1([0.999e-3, 1.001e-3]),
                               rtol=1e-13)
    assert bernoulli([800.0])[0] == pytest.approx(800.0 * np.exp(-800.0), abs=1e-300)


@pytest.mark.parametrize("scheme", ["exponential", "upwind"])
@pytest.mark.parametrize("boundary", ["wall", "open"])
def test_operator_is_conservative_m_matrix(scheme, boundary):
    rng = np.random.default_rng(3)
    occ, wind, outlets = _random_map(rng)
    geo = GridMap(occ, 0.2)
    wind[occ] = 0.0
    A, index = advection_diffusion_operator(geo, wind, outlets=outlets, diffusivity=0.03, lifetime=7.0, boundary=boundary, scheme=scheme)
    dense = A.toarray()
    off = dense - np.diag(np.diag(dense))
    assert (off <= 0).all() and (np.diag(dense) > 0).all()  # Z-matrix with positive diagonal
    # column sums: exactly 1/τ for cells with no absorbing face (mass conservation), more otherwise
    col = dense.sum(axis=0)
    absorbing = np.zeros(occ.shape, bool)
    pad = np.pad(outlets, 1)
    for dr, dc in ((0, 1), (0, -1), (1, 0), (-1, 0)):
        absorbing |= pad[1 + dr : 1 + dr + occ.shape[0], 1 + dc : 1 + dc + occ.shape[1]]
    if boundary == "open":
        absorbing[0, :] = absorbing[-1, :] = absorbing[:, 0] = absorbing[:, -1] = True
    inner = np.zeros(A.shape[0], bool)
    inner[index[index >= 0]] = ~absorbing[index >= 0]  # by active-cell number
    np.testing.assert_allclose(col[inner], 1 / 7.0, rtol=1e-12)
    assert (col[~inner] >= 1 / 7.0 * (1 - 1e-12)).all()
    inv = np.linalg.inv(dense)
    assert inv.min() >= -1e-12 * inv.max()  # M-matrix: A⁻¹ ≥ 0


@pytest.mark.parametrize("boundary", ["wall", "open"])
def test_adjoint_rows_equal_forward_solutions_and_dense_inverse(boundary):
    rng = np.random.default_rng(11)
    occ, wind, outlets = _random_map(rng, shape=(10, 13))
    h = 0.25
    m = PlumeModel(occ, resolution=h, wind=wind, outlets=outlets, diffusivity=0.04, lifetime=9.0, boundary=boundary)
    inv = np.linalg.inv(m.operator.toarray())
    idx = m.active_index
    free_cells = np.argwhere(~occ)
    pick = free_cells[rng.choice(len(free_cells), size=6, replace=False)]
    for r, c in pick:
        x = (0.5 + c) * h, (0.5 + r) * h
        g = m.green(x)
        expect = np.zeros(occ.shape)
        if idx[r, c] >= 0:
            expect[idx >= 0] = inv[idx[r, c], idx[idx >= 0]] / h**2  # G(x|s) = (A⁻¹)_{xs} / h²
        np.testing.assert_allclose(g, expect, rtol=1e-10, atol=1e-14 * np.abs(expect).max(initial=1.0))
        fwd = m.concentration(x)  # source at x: c(s' | x) must equal G(s' | x), read column-wise
        col = np.zeros(occ.shape)
        if idx[r, c] >= 0:
            col[idx >= 0] = inv[idx[idx >= 0], idx[r, c]] / h**2
        np.testing.assert_allclose(fwd, col, rtol=1e-10, atol=1e-14 * np.abs(col).max(initial=1.0))
    # reciprocity between the two: G(x|s) from the adjoint equals the forward field of s read at x
    (r1, c1), (r2, c2) = pick[0], pick[1]
    g12 = m.green(((0.5 + c1) * h, (0.5 + r1) * h))[r2, c2]
    f21 = m.concentration(((0.5 + c2) * h, (0.5 + r2) * h))[r1, c1]
    assert g12 == pytest.approx(f21, rel=1e-10, abs=1e-300)


def test_mean_concentration_is_the_posterior_average_of_the_green_rows_and_the_dense_inverse():
    rng = np.random.default_rng(12)
    occ, wind, outlets = _random_map(rng, shape=(10, 13))
    h = 0.25
    m = PlumeModel(occ, resolution=h, wind=wind, outlets=outlets, diffusivity=0.04, lifetime=9.0)
    p = rng.random(occ.shape) ** 4  # uneven, with mass on walls and outlets too (they emit nothing)
    p /= p.sum()
    got = m.mean_concentration(p)
    idx = m.active_index
    inv = np.linalg.inv(m.operator.toarray())
    expect = np.zeros(occ.shape)
    expect[idx >= 0] = inv[idx[idx >= 0]][:, idx[idx >= 0]] @ p[idx >= 0] / h**2  # Σ_s p(s) (A⁻¹)_{xs} / h²
    np.testing.assert_allclose(got, expect, rtol=1e-10, atol=1e-14 * expect.max())
    free = np.flatnonzero(~occ.ravel())
    rows = m.green_rows(free)  # Σ_s p(s) G(x | s), row by row
    np.testing.assert_allclose(got.ravel()[free], rows @ p.ravel(), rtol=1e-10, atol=1e-14 * expect.max())
    assert (got[occ | outlets] == 0).all()
    with pytest.raises(ValueError, match="map's shape"):
        m.mean_concentration(p[:, :-1])
    with pytest.raises(ValueError, match="finite and non-negative"):
        m.mean_concentration(np.where(occ, -1.0, p))
    with pytest.raises(ValueError, match="finite and non-negative"):
        m.mean_concentration(np.full(occ.shape, np.nan))


def test_green_is_zero_on_walls_outlets_and_across_sealed_walls():
    occ = np.zeros((8, 15), bool)
    occ[:, 7] = True  # sealed wall: two disconnected rooms
    outlets = np.zeros_like(occ)
    outlets[0, 0] = True
    m = PlumeModel(occ, resolution=0.1, outlets=outlets, diffusivity=0.02, lifetime=20.0)
    g = m.green((1.05, 0.45))  # sensor in the right room
    assert (g[occ] == 0).all() and g[0, 0] == 0
    assert (g[:, :7] == 0).all()  # exactly zero from the other room
    assert (g[:, 8:] > 0).all()
    assert (m.green((0.05, 0.05)) == 0).all()  # sensor on an outlet: absorbed, no reading possible
    # opening a door makes the other room contribute
    occ2 = occ.copy()
    occ2[3:5, 7] = False
    g2 = PlumeModel(occ2, resolution=0.1, outlets=outlets, diffusivity=0.02, lifetime=20.0).green((1.05, 0.45))
    assert (g2[:, :7][~occ2[:, :7] & ~outlets[:, :7]] > 0).all()


def test_the_factorisation_is_made_on_first_use_and_kept():
    occ, wind, outlets = _random_map(np.random.default_rng(4))
    m = PlumeModel(occ, resolution=0.1, wind=wind, outlets=outlets)
    assert m._lu_factors is None  # a model never solved pays no factorisation
    g = m.green_rows([np.flatnonzero(~occ.ravel() & ~outlets.ravel())[0]])
    lu = m.factor
    assert lu is not None and m.factor is lu and m.n_solves == 1
    fresh = PlumeModel(occ, resolution=0.1, wind=wind, outlets=outlets)
    fresh.factor  # factorised before the first solve: the same rows
    np.testing.assert_array_equal(g, fresh.green_rows([np.flatnonzero(~occ.ravel() & ~outlets.ravel())[0]]))


def test_a_green_row_is_the_same_bits_solved_alone_or_with_others():
    """A row G(x | ·) does not depend on which other sensor cells share its solve (one chunk, several chunks or
    alone) nor on the cache: what lets an estimator solve its rows together and keep them (the PMFS reading
    ratio)."""
    occ, wind, outlets = _random_map(np.random.default_rng(8), shape=(30, 41))
    cells = np.flatnonzero(~occ.ravel() & ~outlets.ravel())[::3]
    assert cells.size > 64  # more than one chunk of right-hand sides
    together = PlumeModel(occ, resolution=0.1, wind=wind, outlets=outlets, cache_size=0).green_rows(cells)
    alone_model = PlumeModel(occ, resolution=0.1, wind=wind, outlets=outlets, cache_size=0)
    alone = np.stack([alone_model.green_rows([c])[0] for c in cells])
    assert together.tobytes() == alone.tobytes()
    cached = PlumeModel(occ, resolution=0.1, wind=wind, outlets=outlets)
    cached.green_rows(cells[::5])
    assert cached.green_rows(cells[::-1]).tobytes() == together[::-1].tobytes()


def test_adding_absorbing_outlets_lowers_every_green_value():
    rng = np.random.default_rng(5)
    occ, wind, _ = _random_map(rng, shape=(12, 12))
    out1 = np.zeros_like(occ)
    out1[~occ] = rng.random(int((~occ).sum())) < 0.03
    out2 = out1.copy()
    extra = np.argwhere(~occ & ~out1)[:3]
    out2[tuple(extra.T)] = True
    kw = dict(resolution=0.2, wind=wind, diffusivity=0.05, lifetime=10.0)
    x = tuple(((np.argwhere(~occ & ~out2)[-1][::-1]) + 0.5) * 0.2)
    g1, g2 = PlumeModel(occ, outlets=out1, **kw).green(x), PlumeModel(occ, outlets=out2, **kw).green(x)
    assert (g2 <= g1 * (1 + 1e-12)).all() and (g2 < g1).any()


# --- Vergassola et al. (2007) analytic solution -------------------------------------------------------------------
def test_encounter_rate_matches_the_papers_formula_for_wind_along_minus_y():
    d, tau, v, r_emit, a = 0.7, 12.0, 0.9, 3.0, 0.05
    lam = np.sqrt(d * tau / (1 + v**2 * tau / (4 * d)))
    rng = np.random.default_rng(0)
    r = rng.normal(size=(50, 2)) * 2
    r0 = rng.normal(size=2)
    paper = r_emit / np.log(lam / a) * np.exp(v * (r0[1] - r[:, 1]) / (2 * d)) * k0(np.hypot(*(r - r0).T) / lam)
    ours = vergassola_encounter_rate(r - r0, wind=(0.0, -v), diffusivity=d, lifetime=tau, emission_rate=r_emit,
                                     sensor_radius=a)
    np.testing.assert_allclose(ours, paper, rtol=1e-12)
    assert correlation_length(diffusivity=d, lifetime=tau, wind_speed=v) == pytest.approx(lam, rel=1e-15)
    kappa = vergassola_encounter_scale(emission_rate=r_emit, sample_time=2.0, diffusivity=d, lifetime=tau,
                                       wind_speed=v, sensor_radius=a)
    conc = vergassola_concentration(r - r0, wind=(0.0, -v), diffusivity=d, lifetime=tau)
    np.testing.assert_allclose(kappa * conc, 2.0 * ours, rtol=1e-12)  # κ G = expected encounters = rate · Δt


def _open_space_error(h, scheme, *, length=12.0, wind=(0.2, 0.05), d=0.1, tau=20.0, r_min=0.3, r_max=1.5):
    n = int(round(length / h))
    occ = np.zeros((n, n), bool)
    w = np.zeros((n, n, 2))
    w[..., 0], w[..., 1] = wind
    m = PlumeModel(occ, resolution=h, wind=w, diffusivity=d, lifetime=tau, boundary="open", scheme=scheme)
    x = (n // 2 + 0.5) * h, (n // 2 + 0.5) * h
    g = m.green(x)  # G(x | s) for every source cell s
    centres = m.geometry.cell_centres()
    disp = np.asarray(x) - centres  # r − r0 = sensor − source
    ana = vergassola_concentration(disp, wind=wind, diffusivity=d, lifetime=tau)
    dist = np.hypot(disp[..., 0], disp[..., 1])
    ring = (dist >= r_min - 1e-9) & (dist <= r_max)
    return np.abs(g[ring] / ana[ring] - 1).max()


def test_open_space_green_matches_bessel_k0_and_converges():
    """Sources 0.3-1.5 m from the sensor (≥ 3 cells at h = 0.1 m), uniform oblique wind, 12 m x 12 m domain.

    Measured: max relative error 0.95 % at h = 0.1 m, 0.19 % at h = 0.05 m (second order: ratio ≈ 5).
    """
    e_coarse = _open_space_error(0.1, "exponential")
    e_fine = _open_space_error(0.05, "exponential")
    assert e_coarse < 0.012
    assert e_fine < 0.003
    assert e_coarse / e_fine > 3.5  # second-order convergence (4 in the asymptotic limit)


def test_upwind_scheme_is_only_first_order():
    """First-order upwinding adds numerical diffusion |u| h / 2: 27 % / 13 % error, ratio ≈ 2."""
    e_coarse = _open_space_error(0.1, "upwind")
    e_fine = _open_space_error(0.05, "upwind")
    assert 0.1 < e_coarse < 0.35 and 1.7 < e_coarse / e_fine < 2.5
    assert e_fine > 5 * _open_space_error(0.05, "exponential")


# --- bad input -------------------------------------------------------------------------------------------------------
def test_bad_inputs_raise_with_clear_messages():
    occ = np.zeros((4, 5), bool)
    with pytest.raises(TypeError, match="occupancy must be a boolean"):
        PlumeModel(np.full((4, 5), 0.5), resolution=0.1)
    with pytest.raises(ValueError, match="occupancy must be a non-empty"):
        PlumeModel(np.zeros(5, bool), resolution=0.1)
    with pytest.raises(ValueError, match="no free cell"):
        PlumeModel(np.ones((4, 5), bool), resolution=0.1)
    with pytest.raises(ValueError, match="resolution must be a positive"):
        PlumeModel(occ, resolution=0.0)
    with pytest.raises(ValueError, match=r"origin must be finite \(a finite \(x, y\) pair"):
        PlumeModel(occ, resolution=0.1, origin=(0.0, np.nan))
    with pytest.raises(ValueError, match=r"wind must have shape \(4, 5, 2\)"):
        PlumeModel(occ, resolution=0.1, wind=np.zeros((4, 5)))
    bad = np.zeros((4, 5, 2))
    bad[1, 1, 0] = np.nan
    with pytest.raises(ValueError, match=r"wind must be finite on free cells.*\(1, 1\)"):
        PlumeModel(occ, resolution=0.1, wind=bad)
    occ_w = occ.copy()
    occ_w[1, 1] = True
    PlumeModel(occ_w, resolution=0.1, wind=bad)  # NaN inside a wall is ignored
    with pytest.raises(ValueError, match="diffusivity must be a positive"):
        PlumeModel(occ, resolution=0.1, diffusivity=-1.0)
    with pytest.raises(ValueError, match="lifetime must be a positive finite"):
        PlumeModel(occ, resolution=0.1, lifetime=np.inf)
    with pytest.raises(TypeError, match="encounter_scale must be a positive number"):
        PlumeModel(occ, resolution=0.1, encounter_scale="1")
    with pytest.raises(ValueError, match="scheme must be one of"):
        PlumeModel(occ, resolution=0.1, scheme="central")
    with pytest.raises(ValueError, match="boundary must be one of"):
        PlumeModel(occ, resolution=0.1, boundary="periodic")
    with pytest.raises(ValueError, match="outlets must be free cells"):
        PlumeModel(occ_w, resolution=0.1, outlets=occ_w)
    with pytest.raises(ValueError, match="outlets must have the map's shape"):
        PlumeModel(occ, resolution=0.1, outlets=np.zeros((5, 4), bool))
    m = PlumeModel(occ_w, resolution=0.1, origin=(1.0, 2.0))
    with pytest.raises(ValueError, match="outside the map"):
        m.green((0.5, 2.1))
    with pytest.raises(ValueError, match=r"occupied cell \(1, 1\)"):
        m.green((1.15, 2.15))
    with pytest.raises(ValueError, match=r"\(x, y\) pair"):
        m.green((1.15, 2.15, 0.0))
    with pytest.raises(TypeError, match="rng must be a numpy Generator"):
        m.sample_hits([(1.05, 2.05)], (1.25, 2.05), rng=None)
    with pytest.raises(ValueError, match="sensor_radius must be smaller"):
        vergassola_encounter_scale(emission_rate=1, sample_time=1, diffusivity=0.1, lifetime=1, wind_speed=0,
                                   sensor_radius=5.0)
