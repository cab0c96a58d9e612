"""Wind from a lattice Boltzmann CFD solver (lbmpy): time-resolved 2-D flow through the house at sensor height.

The flow is solved by `lbmpy <https://pypi.org/project/lbmpy/>`_ (Bauer et al. 2021, "lbmpy: Automatic code
generation for efficient parallel lattice Boltzmann methods", J. Comput. Sci. 49:101269), which generates and
compiles C kernels (gcc, through pystencils) for a D2Q9 single-relaxation-time (BGK) lattice with the
Smagorinsky subgrid model, on the house's own grid (one lattice node per map cell):

* **obstacles** (no-slip, half-way bounce-back): the walls, the border of the map and every object whose
  height range holds the gas sensor's height :data:`SENSOR_HEIGHT`, except legged furniture
  (:data:`OPEN_BELOW`: tables and chairs, whose space under the top is open to the air);
* **inlets** (velocity bounce-back, "UBB"): the house's inlet window cells blow into the house along the
  window's inward normal at ``speed`` times a seeded gust (below);
* **outlets** (pressure, fixed density ρ = 1): the outlet window cells.

Units. With the map resolution Δx (m) and the nominal inlet speed U (m/s), the inlet's lattice speed is
:data:`U_LATTICE` = 0.04, so the time step is Δt = 0.04 Δx / U (0.02 s for 0.1 m cells at 0.2 m/s) and the
inlet's Mach number stays u / c_s ≤ 0.04 · 1.8 · √3 ≈ 0.12 at the strongest gust (c_s = 1/√3; gusts are capped at
1.8 U); jets through doors and past furniture are faster (over 600 s the fastest cell reached 0.76 m/s, lattice
0.15, in the default house and 1.14 m/s, lattice 0.23, beside the outlet window of ``generate_house(1)``), and a
lattice speed above 0.4 anywhere (Mach 0.7) stops the run with a ValueError. A window N cells wide lets in
U (1 − 1/(3N)) on average, not U: its two end cells lose their diagonal links to the wall (measured in the
channel-flow test). A lattice velocity u_lb is u_lb · Δx / Δt m/s.

Viscosity and turbulence. Air's kinematic viscosity (1.5e-5 m²/s) at Δx = 0.1 m would put the BGK relaxation
time at τ = 0.5 + 3ν Δt/Δx² ≈ 0.50001, where the scheme is unstable: the flow is under-resolved, as any
house-scale CFD of indoor air is. The lattice runs at τ0 = 1/ω0 with ω0 = :data:`OMEGA0` = 1.95 (lattice viscosity
ν0 = (τ0 − 1/2)/3 ≈ 4.3e-3, i.e. ν0 = 0.107 Δx U m²/s: 2.1e-3 m²/s at 0.1 m and 0.2 m/s), and the
Smagorinsky model (Smagorinsky 1963, Mon. Weather Rev. 91:99) adds ν_t = (C_s Δx)² |S| where the resolved shear
is strong, with C_s = :data:`SMAGORINSKY` = 0.1, Deardorff's (1970, J. Fluid Mech. 41:453) value for
wall-bounded flow. Both are eddy viscosities of the size indoor-air models use: Chen and Xu's (1998, Energy and
Buildings 28:137) zero-equation model gives ν_t = 0.03874 V l ≈ 8e-3 m²/s at V = 0.2 m/s, l = 1 m from a wall.
The Reynolds number of a 1 m door is then U·1 m/ν0 ≈ 90: jets through doors and windows separate and shed
eddies, so the flow is unsteady even without gusts.

Gust. The inlet speed factor g and the inflow angle θ (from the inward normal) follow AR(1) processes with a
value every :data:`GUST_STEP` s, interpolated linearly in between (the inlet is set 5 times a second, so its
speed has no steps), with correlation time :data:`GUST_TIME` = 20 s, a speed standard deviation of
:data:`GUST_INTENSITY` = 0.2 (turbulence intensities of the atmospheric surface layer are 0.1-0.3; Stull 1988,
"An Introduction to Boundary Layer Meteorology", Kluwer) and an angle standard deviation of :data:`GUST_ANGLE`
= 10° (a window frame straightens the inflow); g is clipped to [0.3, 1.8].

The flow starts at rest and runs :data:`SPIN_UP` = 120 s (about one flow-through of a house at 0.2 m/s) before the
first snapshot. Each snapshot is the instantaneous cell velocity; window cells take the velocity of the nearest
fluid cell (so a filament is carried into the outlet), obstacles have zero wind.

Sensor height. The gas, the sensor and this flow are 2-D at the height of a ground robot's gas sensor,
:data:`SENSOR_HEIGHT` = 0.3 m. At 0.3 m a bed, a couch, a countertop or an oven blocks the air; under a table or a
chair the air is free (a box of the object list would block it, so :data:`OPEN_BELOW` lists the legged classes).
A 3-D solve would add flow over the furniture and under the doors' lintels, a vertical profile, and thermal
plumes (an oven's), none of which a slice holds.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
from pathlib import Path

import numpy as np
import scipy.ndimage as ndi

from .._shared._fpenv import preserved_float_environment
from .._shared._validate import positive
from ..geometry._grid import GridMap
from ._house import House
from ._wind import WindField, WindSequence

__all__ = ["GUST_ANGLE", "GUST_INTENSITY", "GUST_STEP", "GUST_TIME", "OMEGA0", "OPEN_BELOW", "SENSOR_HEIGHT",
           "SMAGORINSKY", "SPIN_UP", "U_LATTICE", "cfd_obstacles", "cfd_wind", "default_cache_dir"]

#: Height of the gas sensor (and of the 2-D flow and gas), metres above the floor.
SENSOR_HEIGHT = 0.3
#: Classes open below their top (legs only): never an obstacle at the sensor's height.
OPEN_BELOW = frozenset({"chair", "dining table", "table", "desk", "bench", "stool"})
#: Lattice speed of the nominal inlet speed (Mach 0.069).
U_LATTICE = 0.04
#: BGK relaxation rate of the base viscosity (τ0 = 1/ω0).
OMEGA0 = 1.95
#: Smagorinsky constant C_s.
SMAGORINSKY = 0.1
#: Seconds of flow before the first snapshot.
SPIN_UP = 120.0
#: Gust: seconds between updates, correlation time (s), speed std (fraction), angle std (degrees).
GUST_STEP = 1.0
GUST_TIME = 20.0
GUST_INTENSITY = 0.2
GUST_ANGLE = 10.0
_GUST_CLIP = (0.3, 1.8)
_GUST_SUBSTEPS = 5  # inlet updates per knot interval, interpolating linearly
_MAX_LATTICE_SPEED = 0.4  # beyond Mach ~0.7 the lattice is no longer a model of incompressible flow
_SCHEME = "psgsl-lbm-d2q9-srt-smagorinsky-1"  # bump when the set-up changes what is computed


_LAST: dict = {}  # "wind": (cache entry's path, WindSequence) of the last call in this process


def _lbmpy():
    """Import lbmpy (the ``cfd`` extra), with a one-line message when it is missing."""
    try:
        import lbmpy
        import pystencils
    except ImportError:
        raise ImportError('the CFD wind needs lbmpy: pip install "psgsl-pgm[cfd]"') from None
    return lbmpy, pystencils


def _check_compiler() -> None:
    """pystencils compiles lbmpy's kernels with the system's C compiler; without one it fails with an IndexError."""
    from pystencils.jit.cpu.compiler_info import CompilerInfo

    if not CompilerInfo.get_available_compilers():
        raise ImportError("the CFD wind compiles lbmpy's kernels with a C compiler and none was found: install gcc "
                          "(apt-get install gcc)")


def default_cache_dir() -> Path:
    """The CFD wind cache: ``psgsl_pgm/cfd_wind`` in the user cache folder, beside numba's (``~/.cache`` on Linux)."""
    from numba.misc.appdirs import AppDirs

    return Path(AppDirs("psgsl_pgm", appauthor=False).user_cache_dir) / "cfd_wind"


def cfd_obstacles(house: House, *, height: float = SENSOR_HEIGHT) -> np.ndarray:
    """(H, W) bool: the no-slip cells of the CFD at ``height``: walls and the objects that block the air there.

    An object blocks where its footprint lies and ``z_min <= height < z_max``, unless its class is in
    :data:`OPEN_BELOW` (tables and chairs: legs only below the top). Window cells are never obstacles.

    Examples
    --------
    >>> from psgsl_pgm.sim import default_house
    >>> h = default_house()
    >>> m = cfd_obstacles(h)
    >>> [bool(m[tuple(h.grid.world_to_cell(xy))]) for xy in [(3.0, 10.5), (7.7, 2.7)]]  # a bed; under the table
    [True, False]
    """
    if not isinstance(house, House):
        raise TypeError(f"house must be a House, got {type(house).__name__}")
    height = positive(height, "height", "metres")
    out = house.grid.occupancy.copy()
    for o, m in zip(house.objects, house.object_masks):
        z0, z1 = o.z_range
        if o.class_name not in OPEN_BELOW and z0 <= height < z1:
            out |= m
    return out & ~house.inlet & ~house.outlet


def _inward_normals(windows: np.ndarray, fluid: np.ndarray, name: str) -> np.ndarray:
    """(H, W, 2) unit inward normal (x, y) of each window's connected component (zero elsewhere).

    The normal of a component is the mean offset from its cells to their 4-neighbours in ``fluid``.
    """
    h, w = windows.shape
    out = np.zeros((h, w, 2))
    labels, n = ndi.label(windows, structure=np.ones((3, 3), bool))
    for k in range(1, n + 1):
        comp = labels == k
        acc = np.zeros(2)
        for dr, dc in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            shifted = np.zeros_like(fluid)  # shifted[r, c] = fluid[r + dr, c + dc]
            shifted[max(0, -dr):h - max(0, dr), max(0, -dc):w - max(0, dc)] = \
                fluid[max(0, dr):h - max(0, -dr), max(0, dc):w - max(0, -dc)]
            acc += np.count_nonzero(comp & shifted) * np.array([dc, dr], float)  # (x, y) = (col, row)
        norm = np.hypot(*acc)
        if norm == 0:
            r, c = np.argwhere(comp)[0]
            raise ValueError(f"{name} window at cell (row {r}, col {c}) touches no free cell, so no air can pass it")
        out[comp] = acc / norm
    return out


def _gust(n: int, *, rng: np.random.Generator, intensity: float, angle_deg: float, rho: float):
    """(n,) speed factors and (n,) angles (rad): stationary AR(1) with coefficient ``rho``, starting at the mean."""
    g = np.ones(n)
    th = np.zeros(n)
    a = b = 0.0
    s = np.sqrt(1 - rho**2)
    for i in range(1, n):
        a = rho * a + s * rng.standard_normal()
        b = rho * b + s * rng.standard_normal()
        g[i] = 1.0 + intensity * a
        th[i] = np.deg2rad(angle_deg) * b
    return np.clip(g, *_GUST_CLIP), th


def _simulate(obstacle: np.ndarray, inlet: np.ndarray, outlet: np.ndarray, *, resolution: float, speed: float,
              times: np.ndarray, spin_up: float, gust_intensity: float, gust_angle: float, seed: int,
              omega0: float = OMEGA0, smagorinsky: float = SMAGORINSKY) -> np.ndarray:
    """Run the lattice and return (n, H, W, 2) float32 cell velocities (m/s) at ``times`` (s after the spin-up).

    The one set-up of the solver: :func:`cfd_wind` and the channel-flow validation both come through here.
    ``obstacle``, ``inlet`` and ``outlet`` are disjoint (H, W) masks in the map's (row = y, col = x) layout; the
    border of the map is a wall outside them.

    pystencils builds the kernels with gcc's ``-Ofast``, whose start-up code switches the loading thread to flush
    subnormals to zero; the solve runs inside :func:`~psgsl_pgm._shared._fpenv.preserved_float_environment`, so
    the rest of the process computes in IEEE 754 as before it.
    """
    with preserved_float_environment():
        return _run_lattice(obstacle, inlet, outlet, resolution=resolution, speed=speed, times=times,
                            spin_up=spin_up, gust_intensity=gust_intensity, gust_angle=gust_angle, seed=seed,
                            omega0=omega0, smagorinsky=smagorinsky)


def _run_lattice(obstacle, inlet, outlet, *, resolution, speed, times, spin_up, gust_intensity, gust_angle, seed,
                 omega0, smagorinsky) -> np.ndarray:
    """The body of :func:`_simulate` (same arguments and result)."""
    _lbmpy()
    _check_compiler()
    from lbmpy import LBMConfig, LBStencil, Method, Stencil, SubgridScaleModel
    from lbmpy.boundaries import UBB, FixedDensity, NoSlip
    from lbmpy.lbstep import LatticeBoltzmannStep

    h, w = obstacle.shape
    fluid = ~(obstacle | inlet | outlet)
    if not inlet.any() or not outlet.any():
        raise ValueError("the CFD needs at least one inlet and one outlet window cell")
    normals = _inward_normals(inlet, fluid, "inlet")
    _inward_normals(outlet, fluid, "outlet")  # an outlet sealed by furniture is an error too
    dt = U_LATTICE * resolution / speed
    to_ms = resolution / dt

    config = LBMConfig(stencil=LBStencil(Stencil.D2Q9), method=Method.SRT, relaxation_rate=omega0,
                       subgrid_scale_model=(SubgridScaleModel.SMAGORINSKY, smagorinsky), compressible=False)
    step = LatticeBoltzmannStep(domain_size=(w, h), lbm_config=config, name="psgsl")
    dh = step.data_handling
    dh.add_array("u_inlet", values_per_cell=2, dtype=np.float64)
    u_field = dh.fields["u_inlet"]
    bh = step.boundary_handling
    # lattice arrays are indexed [x, y] = the map's [col, row]; the ghost layer (the map's border) is a wall
    wall = np.pad(obstacle.T, 1, constant_values=True)
    win_in = np.pad(inlet.T, 1)
    win_out = np.pad(outlet.T, 1)

    def cells(mask):
        return lambda x, y: mask[np.floor(x).astype(int) + 1, np.floor(y).astype(int) + 1]

    bh.set_boundary(NoSlip(), mask_callback=cells(wall))
    bh.set_boundary(UBB((u_field(0), u_field(1))), mask_callback=cells(win_in))
    bh.set_boundary(FixedDensity(1.0), mask_callback=cells(win_out))
    u_in = dh.cpu_arrays["u_inlet"]  # (w + 2, h + 2, 2) with ghost layers
    n_x, n_y = np.pad(normals[..., 0].T, 1), np.pad(normals[..., 1].T, 1)

    gust_steps = max(1, int(round(GUST_STEP / dt)))
    start = int(round(spin_up / dt))
    targets = start + np.round(np.asarray(times) / dt).astype(np.int64)
    n_gust = int(targets[-1] // gust_steps) + 2 if targets.size else 1
    rng = np.random.default_rng(seed)
    g, th = _gust(n_gust, rng=rng, intensity=gust_intensity, angle_deg=gust_angle,
                  rho=float(np.exp(-gust_steps * dt / GUST_TIME)))

    def set_inlet(i, frac):  # the gust between knots i and i + 1, linearly
        gain = U_LATTICE * ((1 - frac) * g[i] + frac * g[i + 1])
        angle = (1 - frac) * th[i] + frac * th[i + 1]
        c, s = np.cos(angle), np.sin(angle)
        u_in[..., 0] = gain * (c * n_x - s * n_y)
        u_in[..., 1] = gain * (s * n_x + c * n_y)

    out = np.empty((len(targets), h, w, 2), dtype=np.float32)
    # window cells take the velocity of the nearest fluid cell
    _, (ri, ci) = ndi.distance_transform_edt(~fluid, return_indices=True)
    windows = inlet | outlet
    sub = max(1, gust_steps // _GUST_SUBSTEPS)  # inlet updates between knots: no step in the inlet speed
    now = 0
    k = 0
    while k < len(targets):
        stop = min((now // sub + 1) * sub, int(targets[k]))
        if stop > now:
            set_inlet(now // gust_steps, ((now + stop) / 2 % gust_steps) / gust_steps)
            step.run(stop - now)
            now = stop
            if now % gust_steps == 0 or now == targets[k]:
                u = np.asarray(step.velocity_slice(masked=False))[fluid.T]  # obstacle cells hold no velocity
                peak = float(np.max(np.abs(u))) if np.isfinite(u).all() else np.inf
                if not peak <= _MAX_LATTICE_SPEED:
                    raise ValueError(f"the lattice Boltzmann wind diverged at t = {now * dt - spin_up:.1f} s (lattice "
                                     f"speed {peak:.3g} > {_MAX_LATTICE_SPEED}); the openings are too narrow for the "
                                     "grid: resample the house to a finer grid")
        while k < len(targets) and targets[k] == now:
            raw = np.transpose(np.asarray(step.velocity_slice(masked=False)), (1, 0, 2))
            vel = np.zeros((h, w, 2))
            vel[fluid] = raw[fluid] * to_ms
            vel[windows] = vel[ri[windows], ci[windows]]
            out[k] = vel
            k += 1
    return out


def _content_key(obstacle, inlet, outlet, grid: GridMap, **params) -> str:
    """SHA-256 of everything that determines the CFD wind (masks, grid, parameters, constants, solver version)."""
    lbmpy, ps = _lbmpy()
    hsh = hashlib.sha256()
    meta = dict(params, scheme=_SCHEME, shape=list(grid.shape), resolution=float(grid.resolution),
                origin=[float(v) for v in grid.origin], sensor_height=SENSOR_HEIGHT, u_lattice=U_LATTICE,
                omega0=OMEGA0, smagorinsky=SMAGORINSKY, spin_up=SPIN_UP,
                gust=[GUST_STEP, GUST_TIME, GUST_INTENSITY, GUST_ANGLE, list(_GUST_CLIP), _GUST_SUBSTEPS],
                lbmpy=lbmpy.__version__, pystencils=ps.__version__)
    hsh.update(json.dumps(meta, sort_keys=True).encode())
    for m in (obstacle, inlet, outlet):
        hsh.update(np.packbits(np.ascontiguousarray(m, dtype=bool)).tobytes())
    return hsh.hexdigest()


def cfd_wind(house, *, speed: float = 0.2, duration: float = 600.0, seed: int = 0,
             snapshot_period: float = 1.0, cache_dir=None) -> WindSequence:
    """Time-resolved 2-D wind through ``house`` from the lattice Boltzmann solver lbmpy, cached on disk.

    The walls and the objects that block the air at the sensor's height (:func:`cfd_obstacles`) are no-slip
    obstacles, the inlet windows blow at ``speed`` with a seeded slow gust, the outlet windows hold the outdoor
    pressure; the set-up, units, viscosity and turbulence model are stated in :mod:`psgsl_pgm.sim._lbm`.

    Parameters
    ----------
    house : House
        Its grid (one lattice node per cell, Δx = ``house.grid.resolution``), walls, objects and windows.
    speed : float, keyword-only
        Mean inlet speed U, m/s (> 0); the lattice time step is Δt = 0.04 Δx / U.
    duration : float, keyword-only
        Seconds of wind recorded after a 120 s spin-up; the sequence loops after it (as :func:`make_wind`'s).
    seed : int, keyword-only
        Seed of the gust.
    snapshot_period : float, keyword-only
        Seconds between snapshots (each holds for one period); at least one lattice step.
    cache_dir : str or Path, optional, keyword-only
        Folder of the cache (default :func:`default_cache_dir`). The result is stored as ``<sha256>.npz``, keyed by
        the content hash of the obstacle and window masks, the grid, the arguments, the solver constants and the
        lbmpy/pystencils versions; a stored result is loaded without solving.

    Returns
    -------
    WindSequence
        ``ceil(duration / snapshot_period)`` snapshots on ``house.grid`` (velocities stored and returned rounded
        to float32, the same from the solver and from the cache).

    Raises
    ------
    ImportError
        lbmpy is not installed (the ``cfd`` extra), or there is no C compiler (gcc) to build its kernels.
    ValueError
        Bad arguments, a window that no air can pass, or a flow that diverged.

    Examples
    --------
    A solve derives and compiles the lattice kernels (5-8 s) and then runs 8-18 s per house on one core, too long
    for an example here; ``docs/guide/world-models.md`` shows how a world uses it (the ``cfd-wind`` component,
    ``model: realistic``). The arguments are checked before anything is solved:

    >>> from psgsl_pgm.sim import cfd_wind, default_house
    >>> try:
    ...     cfd_wind(default_house(seed=0), speed=-0.2)
    ... except ValueError as err:
    ...     print(err)
    speed must be a positive finite number in m/s, got -0.2
    """
    if not isinstance(house, House):
        raise TypeError(f"house must be a House, got {type(house).__name__}")
    speed = positive(speed, "speed", "m/s")
    duration = positive(duration, "duration", "seconds")
    snapshot_period = positive(snapshot_period, "snapshot_period", "seconds")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise TypeError(f"seed must be an integer, got {seed!r}")
    dt = U_LATTICE * house.grid.resolution / speed
    if snapshot_period < dt:
        raise ValueError(f"snapshot_period must be at least one lattice step ({dt:g} s at this speed and grid), "
                         f"got {snapshot_period!r}")
    n = max(1, int(np.ceil(duration / snapshot_period)))
    obstacle = cfd_obstacles(house)
    key = _content_key(obstacle, house.inlet, house.outlet, house.grid, speed=speed, duration=duration,
                       seed=int(seed), snapshot_period=snapshot_period)
    folder = default_cache_dir() if cache_dir is None else Path(cache_dir)
    path = folder / f"{key}.npz"
    last = _LAST.get("wind")
    if last is not None and last[0] == path:
        return last[1]  # the flow this process used last (a worker runs many episodes of one house in a row)
    with _solving(path):  # one process solves a house; the others wait for its cache entry
        vel = _load(path, (n,) + house.grid.shape + (2,))
        if vel is None:
            vel = _simulate(obstacle, house.inlet, house.outlet, resolution=house.grid.resolution, speed=speed,
                            times=np.arange(n) * snapshot_period, spin_up=SPIN_UP, gust_intensity=GUST_INTENSITY,
                            gust_angle=GUST_ANGLE, seed=int(seed))
            _store(path, vel)
    wind = WindSequence(tuple(WindField(house.grid, v) for v in vel), snapshot_period)  # float64 per snapshot
    _LAST["wind"] = (path, wind)  # read-only snapshots: safe to share between worlds
    return wind


@contextlib.contextmanager
def _solving(path: Path):
    """Hold an exclusive lock on the cache entry's lock file while it is read or solved, so that the workers of a
    grid that need the same house solve it once (the others then load it); without a writable cache folder or
    ``fcntl``, no lock."""
    try:
        import fcntl

        path.parent.mkdir(parents=True, exist_ok=True)
        fh = open(path.with_suffix(".lock"), "a")
    except (ImportError, OSError):
        yield
        return
    with fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def _load(path: Path, shape) -> np.ndarray | None:
    """The cached velocities, or None when absent or unreadable (then they are recomputed and rewritten)."""
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as z:
            vel = z["velocity"]
    except (OSError, ValueError, KeyError, EOFError):
        return None
    if vel.shape != tuple(shape) or vel.dtype != np.float32 or not np.isfinite(vel).all():
        return None
    return vel


def _store(path: Path, vel: np.ndarray) -> None:
    """Write the cache entry atomically (a temporary file, then a rename); a cache that cannot be written is skipped."""
    from ..io._output import write_file_atomically

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError:
        return
    buf = io.BytesIO()
    np.savez_compressed(buf, velocity=vel)
    try:
        write_file_atomically(path, lambda fh: fh.write(buf.getvalue()), option="cache_dir")
    except ValueError:
        return  # a read-only cache folder: the wind is still returned, only not stored

