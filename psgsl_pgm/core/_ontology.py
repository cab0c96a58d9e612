"""The ontology: p(o | s, γ), p(o) and p(o | room) by name (Sec. "Semantic Knowledge and Ontology")."""

from __future__ import annotations

from pathlib import Path
from types import MappingProxyType

import numpy as np
import yaml

from .._shared._validate import SUM_RTOL, as_float_array, check_distribution, describe, unit_interval
from .._shared._validate import names as _vocab_names
from ..io._yaml import load_yaml

__all__ = ["Ontology", "OTHER"]

#: The catch-all class for every object (or empty floor) that the ontology does not list.
OTHER = "other"
_TOL = SUM_RTOL[np.dtype(np.float64)]
_KEYS = {"classes", "class_prior", "gases", "rooms"}


class Ontology:
    r"""Object classes, gas types and the probabilities that relate them.

    Parameters
    ----------
    classes : sequence of str
        Object class names; :data:`OTHER` ("other") is appended when absent — it stands for everything not
        listed (including empty floor), so k = len(classes) (+1).
    gases : sequence of str
        Gas (smell) names :math:`\gamma`.
    source_table : (m, k) array_like
        :math:`p(o \mid s, \gamma)`: row γ is the distribution of the source object's class for gas γ.
    class_prior : (k,) array_like, optional
        :math:`p(o)`, the prior of a cell's class before observing it; uniform when omitted. It is the prior
        under which a semantic map's beliefs are computed; when it equals the background
        :math:`p(o \mid \neg s)` the closed form is exact (see :func:`psgsl_pgm.semantic_source_probability`).
    rooms : sequence of str, optional
        Room-category names.
    room_table : (r, k) array_like, optional
        :math:`p(o \mid \text{room})`, one row per room.

    Examples
    --------
    >>> from psgsl_pgm import Ontology
    >>> ont = Ontology.from_dict({"classes": ["oven", "sink"],
    ...                           "gases": {"smoke": {"oven": 0.9, "sink": 0.1}}})
    >>> ont.classes
    ('oven', 'sink', 'other')
    >>> ont.source_likelihood("smoke")
    array([0.9, 0.1, 0. ])
    """

    def __init__(self, classes, gases, source_table, class_prior=None, rooms=(), room_table=None):
        classes = _names(classes, "classes")
        if OTHER not in classes:
            classes = classes + (OTHER,)
        k = len(classes)
        gases = _names(gases, "gases")
        table = as_float_array(source_table, "source_table", dtype=np.float64, ndim=2)
        if table.shape == (len(gases), k - 1) and OTHER not in _names(classes[:-1], "classes"):
            table = np.column_stack([table, np.zeros(len(gases))])  # "other" appended: give it zero
        if table.shape != (len(gases), k):
            raise ValueError(f"source_table must have shape ({len(gases)}, {k}) (gases × classes), got {describe(table)}")
        check_distribution(table, "source_table (each gas row, p(o | s, γ))")
        if class_prior is None:
            prior = np.full(k, 1.0 / k)
        else:
            prior = as_float_array(class_prior, "class_prior", dtype=np.float64, ndim=1)
            if prior.shape == (k - 1,):
                raise ValueError(f"class_prior must include the '{OTHER}' class: shape ({k},), got {describe(prior)}")
            if prior.shape != (k,):
                raise ValueError(f"class_prior must have shape ({k},), got {describe(prior)}")
            check_distribution(prior, "class_prior")
        rooms = _names(rooms, "rooms") if rooms else ()
        if room_table is None:
            if rooms:
                raise ValueError(f"room_table (shape ({len(rooms)}, {k})) is required with rooms {list(rooms)}")
            rtable = np.zeros((0, k))
        else:
            rtable = as_float_array(room_table, "room_table", dtype=np.float64, ndim=2)
            if rtable.shape != (len(rooms), k):
                raise ValueError(f"room_table must have shape ({len(rooms)}, {k}) (rooms × classes), got {describe(rtable)}")
            check_distribution(rtable, "room_table (each room row, p(o | room))")
        for what, arr in (("source_table", table), ("room_table", rtable)):
            bad = (prior == 0) & (arr > 0).any(axis=0)
            if np.any(bad):
                raise ValueError(
                    f"class_prior is zero for {[classes[i] for i in np.flatnonzero(bad)]} which {what} makes possible"
                )
        self._classes, self._gases, self._rooms = classes, gases, rooms
        self._table, self._prior, self._room_table = table, prior, rtable
        for arr in (table, prior, rtable):
            arr.setflags(write=False)
        self._class_index = MappingProxyType({c: i for i, c in enumerate(classes)})

    # ----------------------------------------------------------------------------------------- accessors
    classes = property(lambda self: self._classes, doc="Class names, tuple of str (``'other'`` included).")
    gases = property(lambda self: self._gases, doc="Gas names γ, tuple of str.")
    rooms = property(lambda self: self._rooms, doc="Room-category names, tuple of str.")
    class_prior = property(lambda self: self._prior, doc="p(o), (k,) read-only ndarray.")
    room_table = property(lambda self: self._room_table, doc="p(o | room), (r, k) read-only ndarray.")
    source_table = property(lambda self: self._table, doc="p(o | s, γ), (m, k) read-only ndarray.")

    def __repr__(self) -> str:
        return f"Ontology(classes={list(self._classes)}, gases={list(self._gases)}, rooms={list(self._rooms)})"

    def __eq__(self, other) -> bool:
        if not isinstance(other, Ontology):
            return NotImplemented
        return self.to_dict() == other.to_dict()

    __hash__ = None

    def class_index(self, name: str) -> int:
        """Index of class ``name`` in :attr:`classes`."""
        return _lookup(self._class_index, name, "class")

    def gas_index(self, name: str) -> int:
        """Index of gas ``name`` in :attr:`gases`."""
        return _lookup({g: i for i, g in enumerate(self._gases)}, name, "gas")

    def room_index(self, name: str) -> int:
        """Index of room ``name`` in :attr:`rooms`."""
        return _lookup({r: i for i, r in enumerate(self._rooms)}, name, "room")

    def source_likelihood(self, gas=None, *, off_ontology: float = 0.0) -> np.ndarray:
        r""":math:`p(o \mid s, \gamma)` for one gas name, (k,); for a list of names, (len, k); for ``None`` all
        gases, (m, k).

        Parameters
        ----------
        gas : str, list of str or None
        off_ontology : float in [0, 1], keyword-only
            :math:`\varepsilon`, the probability that a source is *off the ontology*: emitted by whatever is in
            its cell, the cell's object then following the background :math:`p(o \mid \neg s)` =
            :attr:`class_prior` as any other cell's does. Marginalising that latent choice out of the source
            cell's CPD gives

            .. math:: p_\varepsilon(o_{ci} \mid s_c, \gamma) = (1 - \varepsilon)\, p(o_{ci} \mid s_c, \gamma)
                      + \varepsilon\, p(o_{ci} \mid \neg s_c),

            so eq. (20) with this likelihood is exact for the mixture (in Network A with background
            :math:`\beta` = :attr:`class_prior`, as without :math:`\varepsilon`). The semantic weight of a cell
            becomes

            .. math:: (1 - \varepsilon) \sum_i \frac{p(o_{ci} \mid z_c)}{p(o_{ci})}\, p(o_{ci} \mid s_c)
                      + \varepsilon,

            so no cell falls below :math:`\varepsilon` times the weight of a cell the camera has not seen: an
            object-free source cell keeps mass that the gas can raise. 0 (the default): the ontology as it
            stands.

        Examples
        --------
        >>> from psgsl_pgm import kitchen_ontology
        >>> kitchen_ontology().source_likelihood("smoke", off_ontology=0.1).round(3).tolist()
        [0.38, 0.245, 0.29, 0.065, 0.02]
        """
        eps = unit_interval(off_ontology, "off_ontology")
        if gas is None:
            table = self._table.copy()
        elif isinstance(gas, str):
            table = self._table[self.gas_index(gas)].copy()
        else:
            table = self._table[[self.gas_index(g) for g in gas]]
        if eps:
            table = (1.0 - eps) * table + eps * self._prior  # p_ε(o | s, γ) = (1 − ε) p(o | s, γ) + ε p(o | ¬s)
        return table

    def room_likelihood(self, room: str) -> np.ndarray:
        """p(o | room) for a room name, (k,)."""
        return self._room_table[self.room_index(room)].copy()

    def marginal_class_prior(self, n_cells: int, gas=None) -> np.ndarray:
        r"""The marginal class prior :math:`p(o_n)` of a cell under a uniform source prior.

        Eq. (17) of the paper, with :math:`p(s_n) = 1 / n_\text{cells}` and :attr:`class_prior` as the
        background :math:`p(o \mid \neg s)`:

        .. math:: p(o_n) = p(s_n)\, p(o \mid s) + p(\neg s_n)\, p(o \mid \neg s)

        With this prior instead of the background, the closed form is the paper's approximation
        :math:`p(o_{ni} \mid s_c) \simeq p(o_{ni})` (eq. (18)).
        """
        if isinstance(n_cells, (bool, np.bool_)) or not isinstance(n_cells, (int, np.integer)) or n_cells < 1:
            raise ValueError(f"n_cells must be a positive int, got {n_cells!r}")
        lik = self.source_likelihood(self._gases[0] if gas is None and len(self._gases) == 1 else gas)
        if lik.ndim != 1:
            raise ValueError(f"name one gas of {list(self._gases)} for the marginal prior")
        return lik / n_cells + (1 - 1 / n_cells) * self._prior

    # --------------------------------------------------------------------------------------- construction
    @classmethod
    def from_dict(cls, data) -> "Ontology":
        """Build from a mapping (the YAML layout)::

            classes: [oven, microwave, refrigerator, countertop]   # "other" is appended
            class_prior: {oven: 0.1, ...}          # optional; unlisted classes share the rest equally
            gases:
              smoke: {oven: 0.4, microwave: 0.25, refrigerator: 0.3, countertop: 0.05}
            rooms:                                  # optional, p(o | room)
              kitchen: {oven: 0.2, refrigerator: 0.1}

        A gas or room row may list only some classes: the remaining mass 1 − Σ(listed) is shared by the
        unlisted classes in proportion to the class prior. A row whose listed values exceed 1 (tolerance
        1e-6) is refused.
        """
        if not isinstance(data, dict):
            raise TypeError(f"ontology data must be a mapping, got {type(data).__name__}")
        unknown = set(data) - _KEYS
        if unknown:
            raise ValueError(f"unknown ontology keys {sorted(unknown)}; expected some of {sorted(_KEYS)}")
        for key in ("classes", "gases"):
            if key not in data:
                raise ValueError(f"ontology data lacks the required key '{key}'")
        classes = _names(data["classes"], "classes")
        if OTHER not in classes:
            classes = classes + (OTHER,)
        k = len(classes)
        index = {c: i for i, c in enumerate(classes)}
        prior = _row(data.get("class_prior"), index, "class_prior", np.full(k, 1.0)) if "class_prior" in data else None
        weights = prior if prior is not None else np.full(k, 1.0 / k)
        gases = _mapping(data["gases"], "gases")
        table = np.array([_row(row, index, f"gases.{g}", weights) for g, row in gases.items()])
        rooms = _mapping(data.get("rooms") or {}, "rooms")
        rtable = np.array([_row(row, index, f"rooms.{r}", weights) for r, row in rooms.items()]) if rooms else None
        return cls(classes, list(gases), table, prior, rooms=list(rooms), room_table=rtable)

    def to_dict(self) -> dict:
        """Explicit mapping (every class listed) that :meth:`from_dict` reads back to an equal ontology."""

        def row(values):
            return {c: float(v) for c, v in zip(self._classes, values)}

        out = {"classes": list(self._classes), "class_prior": row(self._prior),
               "gases": {g: row(r) for g, r in zip(self._gases, self._table)}}
        if self._rooms:
            out["rooms"] = {r: row(v) for r, v in zip(self._rooms, self._room_table)}
        return out

    @classmethod
    def from_yaml(cls, path, *, room_classes=None) -> "Ontology":
        """Read an ontology file: this project's layout (:meth:`from_dict`) or the lab's (top-level ``Gases``).

        The lab's layout (MAPIRlab ``ontology.yaml``: ``Gases: [{gas, probs: {class: p, ..., other: p}}]``) is
        read as the lab's code reads it — values normalised per gas, ``other`` the catch-all of every class the
        gas does not list; see :mod:`psgsl_pgm.io._ontology_lab`. Class names of the lab layout go through the COCO
        alias table (:func:`psgsl_pgm.io._coco.canonical_class`).

        Parameters
        ----------
        path : str or Path
        room_classes : str or Path, optional, keyword-only
            The lab's ``ObjectProbByRoom.yaml`` (``number_classes``, ``room_categories``): p(o | room) for the
            rooms it lists (rooms it does not list get the class prior when beliefs are built from a room map)
            and, for a lab-layout ontology, the class prior 1 / number_classes. With this project's layout the
            file's ``class_prior`` is kept and the file must not have ``rooms`` of its own.

        Raises
        ------
        FileNotFoundError
            No such file.
        ValueError
            Unreadable, non-UTF-8 or malformed files, duplicate keys, integers too large for a float, unknown or
            missing keys, bad numbers — the message starts with the file and names the key.
        """
        path = Path(path)
        data = _read_yaml(path, "ontology")
        room_data = None if room_classes is None else _read_yaml(Path(room_classes), "room-classes")
        from ..io._ontology_lab import is_lab_format, lab_key_typo, lab_ontology, lab_room_table

        if is_lab_format(data):
            try:
                args = lab_ontology(data, str(path), room_data=room_data, room_where=str(room_classes))
                return cls(args.pop("classes"), args.pop("gases"), args.pop("source_table"), **args)
            except (ValueError, TypeError) as exc:
                msg = str(exc)
                raise type(exc)(msg if msg.startswith((str(path), str(room_classes))) else f"{path}: {msg}") from None
        typo = lab_key_typo(data, sorted(_KEYS))
        if typo is not None:
            raise ValueError(f"{path}: {typo}")
        try:
            ont = cls.from_dict(data)
        except (ValueError, TypeError) as exc:
            raise type(exc)(f"{path}: {exc}") from None
        if room_data is None:
            return ont
        if ont.rooms:
            raise ValueError(f"{path}: key 'rooms' is given, and so is the room-classes file {room_classes}; use one")
        _, rooms, table = lab_room_table(ont.classes, room_data, str(room_classes))
        return cls(ont.classes, ont.gases, ont.source_table, ont.class_prior, rooms=rooms, room_table=table)

    def to_yaml(self, path=None):
        """Write to ``path`` (or return the YAML text when ``path`` is None)."""
        text = yaml.safe_dump(self.to_dict(), sort_keys=False, allow_unicode=True)
        if path is None:
            return text
        Path(path).write_text(text)
        return None

    @classmethod
    def from_counts(cls, counts, *, classes, concentration=1.0, class_prior=None, rooms=None) -> "Ontology":
        """Frequentist estimate of p(o | s, γ) from counts of known releases (Sec. "Semantic Knowledge").

        For each gas, the posterior mean under a symmetric Dirichlet(``concentration``) prior:
        p(o_i | s, γ) = (n_γi + α) / (N_γ + k α). ``concentration=0`` gives the maximum-likelihood estimate
        (classes never seen as a source then get probability 0).

        Parameters
        ----------
        counts : mapping of str to mapping of str to int
            ``{gas: {class: number of known releases from an object of that class}}``.
        classes : sequence of str
            All classes ("other" appended when absent); unlisted classes in a gas's counts count 0.
        concentration : float, default 1.0
            Dirichlet pseudo-count α ≥ 0 per class.
        class_prior, rooms
            As for :meth:`from_dict` (mappings by name).
        """
        alpha = _number(concentration, "concentration")
        if alpha < 0:
            raise ValueError(f"concentration must be a finite number >= 0, got {concentration!r}")
        names = _names(classes, "classes")
        if OTHER not in names:
            names = names + (OTHER,)
        index = {c: i for i, c in enumerate(names)}
        gases = _mapping(counts, "counts")
        table = []
        for gas, row in gases.items():
            n = np.zeros(len(names))
            for name, value in _mapping(row, f"counts.{gas}").items():
                count = _number(value, f"counts.{gas}.{name}")
                if count < 0 or count != int(count):
                    raise ValueError(f"counts.{gas}.{name} must be a non-negative whole number, got {value!r}")
                n[_lookup(index, name, "class", f"counts.{gas}")] = count
            if n.sum() + alpha * len(names) == 0:
                raise ValueError(f"counts.{gas} has no releases and concentration is 0: p(o | s, {gas}) is undefined")
            table.append((n + alpha) / (n.sum() + alpha * len(names)))  # Dirichlet posterior mean
        data = {"classes": list(names), "gases": {g: dict(zip(names, r)) for g, r in zip(gases, table)}}
        if class_prior is not None:
            data["class_prior"] = class_prior
        if rooms is not None:
            data["rooms"] = rooms
        return cls.from_dict(data)


def _read_yaml(path: Path, what: str):
    """The parsed YAML document of an ontology file, by the project's safe loader (:mod:`psgsl_pgm.io._yaml`):
    duplicate keys, huge integers, non-UTF-8 bytes and malformed YAML are ValueErrors naming the file."""
    return load_yaml(path)


# ------------------------------------------------------------------------------------------------ helpers
def _names(values, what) -> tuple:
    return _vocab_names(values, what, allow_empty=(what == "rooms"))  # the shared vocabulary: "ab", dicts, sets refused


def _mapping(value, what) -> dict:
    if not isinstance(value, dict):
        raise TypeError(f"{what} must be a mapping of names, got {type(value).__name__} {value!r}")
    for key in value:
        if not isinstance(key, str):
            raise TypeError(f"{what} must be keyed by names (strings), got key {key!r}")
    return value


def _number(value, what) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{what} must be a number, got {value!r}")
    try:
        v = float(value)
    except OverflowError:  # an int beyond ±1.8e308
        raise ValueError(f"{what} must be finite, got an integer of {value.bit_length()} bits, too large for a float") from None
    if not np.isfinite(v):
        raise ValueError(f"{what} must be finite, got {value!r}")
    return v


def _lookup(index, name, what, where=None) -> int:
    if name not in index:
        at = f" in {where}" if where else ""
        raise ValueError(f"unknown {what} {name!r}{at}; known: {list(index)}")
    return index[name]


def _row(values, index, what, weights) -> np.ndarray:
    """A distribution over classes from a partial mapping; unlisted classes share the rest ∝ ``weights``."""
    values = _mapping(values, what)
    row = np.zeros(len(index))
    listed = np.zeros(len(index), dtype=bool)
    for name, value in values.items():
        v = _number(value, f"{what}.{name}")
        if v < 0:
            raise ValueError(f"{what}.{name} must be non-negative, got {v}")
        i = _lookup(index, name, "class", what)
        row[i], listed[i] = v, True
    rest = 1.0 - row.sum()
    if rest < -_TOL:
        raise ValueError(f"{what} sums to {row.sum():.9g} > 1 (tolerance {_TOL:g})")
    rest = max(rest, 0.0)
    if rest > _TOL:
        share = np.where(listed, 0.0, weights)
        if share.sum() == 0:
            raise ValueError(f"{what} sums to {row.sum():.9g} < 1 and lists every class: it is not normalised")
        row += rest * share / share.sum()
    return row / row.sum()
