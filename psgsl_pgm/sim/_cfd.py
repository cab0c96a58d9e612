"""Reader for CFD wind exports in GADEN's CSV form (ParaView "Points" + "U" columns), snapped to a grid.

GADEN's preprocessing reads OpenFOAM results exported from ParaView as CSV with a header naming the columns,
among them ``"U:0","U:1","U:2"`` (velocity, m/s) and ``"Points:0","Points:1","Points:2"`` (position, m), in
any order and possibly with others (``"p"``, ``"k"``, ...). ParaView versions differ in whether the header
carries units: ``"U:0"`` and ``"U [m/s]:0"`` (``"Points [m]:0"``) are the same column here. Here the points
within a horizontal slab around a height are kept and every free cell of the grid takes the (u, v) of the nearest
of them. Several files are time snapshots (:func:`read_gaden_wind_snapshots`). :func:`write_gaden_wind_csv` writes
a wind field or sequence in the same form (one row per free cell centre), which these readers load back.
"""

from __future__ import annotations

import csv
import io
import re
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from ..geometry._grid import GridMap
from ._wind import WindField, WindSequence

__all__ = ["read_gaden_wind_csv", "read_gaden_wind_snapshots", "write_gaden_wind_csv"]

_COLUMNS = ("U:0", "U:1", "U:2", "Points:0", "Points:1", "Points:2")


def read_gaden_wind_csv(path, *, like: GridMap, height: float, slab: float | None = None,
                        max_distance: float | None = None) -> WindField:
    r"""Read a GADEN/ParaView CFD CSV and snap its horizontal wind at ``height`` onto a grid.

    Parameters
    ----------
    path : str or Path
        CSV with a header row; the six columns ``U:0..2``, ``Points:0..2`` are required (quotes optional).
    like : GridMap, keyword-only
        Grid (and map frame) to snap to.
    height : float, keyword-only
        z of the horizontal slice, metres.
    slab : float, optional, keyword-only
        Points with abs(z − height) <= slab / 2 are used (default: one grid cell, ``like.resolution``).
    max_distance : float, optional, keyword-only
        Free cells farther than this from every slab point get zero wind (default: 2 cells).

    Returns
    -------
    WindField
        Cell velocities (u, v) = (U:0, U:1); zero in walls. No face velocities.

    Raises
    ------
    FileNotFoundError
    ValueError
        Missing columns, non-numeric entries, no point in the slab — naming the file, and the line/column.

    Examples
    --------
    A CSV as ParaView exports it, two points at z = 0.5 m on a grid of two 1 m cells:

    >>> import tempfile
    >>> import numpy as np
    >>> from pathlib import Path
    >>> from psgsl_pgm.sim import GridMap, read_gaden_wind_csv
    >>> text = '"U:0","U:1","U:2","Points:0","Points:1","Points:2"\n0.3,0,0,0.5,0.5,0.5\n0.1,0.2,0,1.5,0.5,0.5\n'
    >>> with tempfile.TemporaryDirectory() as d:
    ...     path = Path(d) / "wind.csv"
    ...     _ = path.write_text(text)
    ...     wind = read_gaden_wind_csv(path, like=GridMap(np.zeros((1, 2), bool), 1.0), height=0.5)
    >>> wind.velocity.tolist()
    [[[0.3, 0.0], [0.1, 0.2]]]
    """
    p = Path(path)
    if not isinstance(like, GridMap):
        raise TypeError(f"like must be a GridMap, got {type(like).__name__}")
    if not p.is_file():
        raise FileNotFoundError(f"{p}: no such file")
    if not np.isfinite(height):
        raise ValueError(f"height must be a finite number of metres, got {height!r}")
    slab = like.resolution if slab is None else float(slab)
    max_distance = 2 * like.resolution if max_distance is None else float(max_distance)
    if not (slab > 0 and max_distance > 0):
        raise ValueError(f"slab and max_distance must be positive, got {slab!r}, {max_distance!r}")
    try:
        with p.open(newline="", encoding="utf-8-sig") as fh:
            reader = csv.reader(fh)
            try:
                raw = next(reader)
                header = [_column(h) for h in raw]
            except StopIteration:
                raise ValueError(f"{p}: empty file, expected a header with columns {list(_COLUMNS)}") from None
            missing = [c for c in _COLUMNS if c not in header]
            if missing:
                raise ValueError(f"{p}: missing column(s) {missing}; the header has {header}")
            cols = [header.index(c) for c in _COLUMNS]
            rows = []
            for line, row in enumerate(reader, start=2):
                if not row or all(not x.strip() for x in row):
                    continue
                try:
                    rows.append([float(row[i]) for i in cols])
                except IndexError:
                    raise ValueError(f"{p}: line {line} has {len(row)} fields, expected {len(header)}") from None
                except ValueError:
                    bad = next(c for c, i in zip(_COLUMNS, cols) if not _is_float(row[i]))
                    raise ValueError(f"{p}: line {line}, column '{bad}': not a number: {row[header.index(bad)]!r}") from None
    except UnicodeDecodeError as exc:  # a ValueError subclass: before the loop's own ValueError handling
        raise ValueError(f"{p}: not UTF-8 text: it holds the byte 0x{exc.object[exc.start]:02x}, which cannot be "
                         "decoded; save the file as UTF-8") from None
    except csv.Error as exc:
        raise ValueError(f"{p}: not a valid CSV file ({exc})") from None
    if len(set(header)) != len(header):
        dup = sorted({h for h in header if header.count(h) > 1} & set(_COLUMNS))
        if dup:
            raise ValueError(f"{p}: column(s) {dup} appear twice in the header {raw}")
    data = np.array(rows, dtype=np.float64).reshape(-1, 6)
    if not np.all(np.isfinite(data)):
        line = int(np.argwhere(~np.isfinite(data))[0, 0]) + 2
        raise ValueError(f"{p}: non-finite value near data row {line - 1}")
    in_slab = np.abs(data[:, 5] - height) <= slab / 2
    if not in_slab.any():
        z = data[:, 5]
        rng = f"[{z.min():g}, {z.max():g}]" if z.size else "(no rows)"
        raise ValueError(f"{p}: no point within {slab / 2:g} m of height {height:g} m; the points' z span {rng}")
    pts = data[in_slab]
    tree = cKDTree(pts[:, 3:5])
    centres = like.cell_centres()[like.free]
    dist, idx = tree.query(centres)
    vel = np.zeros(like.shape + (2,))
    uv = pts[idx, :2]
    uv[dist > max_distance] = 0.0
    vel[like.free] = uv
    return WindField(like, vel)


def read_gaden_wind_snapshots(paths, *, like: GridMap, height: float, period: float = 1.0,
                              slab: float | None = None, max_distance: float | None = None) -> WindSequence:
    """Several GADEN/ParaView CSVs (one per time step, in order) as piecewise-constant wind snapshots.

    Parameters
    ----------
    paths : sequence of str or Path
        One CSV per snapshot (see :func:`read_gaden_wind_csv`); at least one.
    like, height, slab, max_distance
        As :func:`read_gaden_wind_csv`, for every file.
    period : float, keyword-only
        Seconds each snapshot holds (GADEN's wind time step); the sequence loops after the last one.

    Returns
    -------
    WindSequence

    Raises
    ------
    FileNotFoundError
        A file of ``paths`` does not exist.
    ValueError
        ``paths`` is empty, ``period`` is not a positive number, or a file is refused by
        :func:`read_gaden_wind_csv` (the message names the file).
    TypeError
        ``like`` is not a :class:`GridMap`.

    Examples
    --------
    A round trip through :func:`write_gaden_wind_csv` (one file per snapshot):

    >>> import tempfile
    >>> import numpy as np
    >>> from pathlib import Path
    >>> from psgsl_pgm.sim import GridMap, WindField, WindSequence, read_gaden_wind_snapshots, write_gaden_wind_csv
    >>> grid = GridMap(np.zeros((2, 3), bool), 0.5)
    >>> seq = WindSequence((WindField(grid, np.ones((2, 3, 2))), WindField(grid, np.zeros((2, 3, 2)))), 2.0)
    >>> with tempfile.TemporaryDirectory() as d:
    ...     files = write_gaden_wind_csv(Path(d) / "wind", seq, height=0.3)
    ...     back = read_gaden_wind_snapshots(files, like=grid, height=0.3, period=2.0)
    >>> [f.name for f in files], len(back.snapshots)
    (['wind_0.csv', 'wind_1.csv'], 2)
    >>> bool(np.array_equal(back.snapshots[0].velocity, seq.snapshots[0].velocity))
    True
    """
    files = [paths] if isinstance(paths, (str, Path)) else list(paths)
    if not files:
        raise ValueError("paths must name at least one GADEN wind CSV")
    if not (np.isfinite(period) and period > 0):
        raise ValueError(f"period must be a positive number of seconds, got {period!r}")
    snaps = tuple(read_gaden_wind_csv(f, like=like, height=height, slab=slab, max_distance=max_distance)
                  for f in files)
    return WindSequence(snaps, float(period))


def _column(name: str) -> str:
    """Header cell without quotes and units: ``'"U [m/s]:0"'`` -> ``'U:0'``."""
    return re.sub(r"\s*\[[^\]]*\]", "", name.strip().strip('"')).strip()


def _is_float(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return False


def write_gaden_wind_csv(path, wind, *, height: float) -> list:
    """Write wind in GADEN's CSV form: one row per free cell centre at ``height``, columns ``U:0..2``, ``Points:0..2``.

    Parameters
    ----------
    path : str or Path
        For a :class:`WindField`, the file to write. For a :class:`WindSequence`, the file name prefix as in
        GADEN's ``wind_files`` setting: snapshot ``k`` goes to ``<path>_<k>.csv`` (GADEN's numbering from 0).
    wind : WindField or WindSequence
    height : float, keyword-only
        z of every point (the slice's height), metres; ``U:2`` is 0.

    Returns
    -------
    list of Path
        The files written, in snapshot order. Each is written atomically (a temporary file, then a rename).

    Raises
    ------
    ValueError
        ``height`` is not finite.
    TypeError
        ``wind`` is neither a :class:`WindField` nor a :class:`WindSequence`.

    Examples
    --------
    >>> import tempfile, numpy as np
    >>> g = GridMap(np.zeros((2, 3), bool), 0.5)
    >>> f = WindField(g, np.ones((2, 3, 2)))
    >>> with tempfile.TemporaryDirectory() as d:
    ...     [p] = write_gaden_wind_csv(Path(d) / "w.csv", f, height=0.3)
    ...     back = read_gaden_wind_csv(p, like=g, height=0.3)
    >>> bool(np.array_equal(back.velocity, f.velocity))
    True
    """
    from ..io._output import write_file_atomically

    if not np.isfinite(height):
        raise ValueError(f"height must be a finite number of metres, got {height!r}")
    if isinstance(wind, WindField):
        fields, paths = [wind], [Path(path)]
    elif isinstance(wind, WindSequence):
        fields = list(wind.snapshots)
        paths = [Path(f"{path}_{k}.csv") for k in range(len(fields))]
    else:
        raise TypeError(f"wind must be a WindField or WindSequence, got {type(wind).__name__}")
    for field, p in zip(fields, paths):
        g = field.grid
        xy = g.cell_centres()[g.free]
        uv = field.velocity[g.free]
        table = np.column_stack([uv, np.zeros(len(uv)), xy, np.full(len(uv), float(height))])
        text = io.StringIO()
        text.write(",".join(f'"{c}"' for c in _COLUMNS) + "\n")
        np.savetxt(text, table, delimiter=",", fmt="%.17g")
        data = text.getvalue().encode()
        write_file_atomically(p, lambda fh, data=data: fh.write(data), option="path")
    return paths
