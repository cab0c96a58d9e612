r"""The robot declares where the source is: one rule for every policy, and how a declaration is scored.

**The rule.** After each stop the robot takes its variant's posterior p(s | g, z, F) (p(s | g, F) for the
``olfaction`` variant), the most probable hypothesis c* = argmax_c p(c), and the declared region D(c*): every
cell whose centre lies within ``radius`` (0.5 m) of c*'s found region R(c*) (:class:`DetectionModel`: the
footprint of the object that owns c*, or c* itself). It declares c* when

.. math:: M = \sum_{c \in D(c^*)} p(c) \ \ge\ \kappa

(κ = ``declare_mass``, 0.9). Why this rule: M is the robot's own probability that the source lies within
``radius`` of what it names, so with a calibrated posterior a declaration at κ is right with probability at
least κ, and the rule needs nothing a policy may lack — the reactive baselines and the semantics-alone policies
declare with it as infotaxis does. Declaring at an object (the oven) asks for the object's mass, not one cell's:
a source object's probability is spread over its footprint. The close-range detector
(:class:`psgsl_pgm.sim.SourceDetector`) is evidence like any other — a detection conditions the posterior on the
hypotheses found where it fired (:meth:`DetectionModel.found_log_likelihood`) — so after a detection the rule
usually declares at once, but it need not: when the detection leaves two neighbouring objects, the robot looks
again.

**Scoring** (GSL-Bench's criterion). The declared point is c*'s cell centre; its error is the distance to the
true source point, or to the nearest cell centre of the source object's footprint for an object source; the
declaration is right when the error is at most ``success_radius`` (1.0 m). The run ends at the first
declaration, right or wrong: a wrong one is a failure. Going on with the declared place ruled out would reward a
robot that declares early and often — a responder sent to the wrong room has already been sent.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage as ndi

__all__ = ["Declaration", "declaration_error", "propose_declaration"]


@dataclass(frozen=True)
class Declaration:
    """The hypothesis the robot would declare now, and the mass that backs it.

    Attributes
    ----------
    cell : int
        c*, flat index of the most probable cell.
    xy : (2,) ndarray
        c*'s cell centre, m (the declared point).
    mass : float
        M, the posterior mass of the declared region D(c*).
    """

    cell: int
    xy: np.ndarray
    mass: float


def declared_region(detection, cell: int, radius: float) -> np.ndarray:
    """(H, W) bool D(c): cells whose centre lies within ``radius`` m of a cell centre of R(c)."""
    region = detection.region_mask(cell)
    res = detection.grid.resolution
    pad = int(np.ceil(radius / res)) + 1
    rows, cols = np.nonzero(region)
    r0, r1 = max(rows.min() - pad, 0), min(rows.max() + pad + 1, region.shape[0])
    c0, c1 = max(cols.min() - pad, 0), min(cols.max() + pad + 1, region.shape[1])
    window = region[r0:r1, c0:c1]
    out = np.zeros_like(region)
    # distance from each cell centre to the nearest centre of R(c) (a window around it holds every cell within reach)
    out[r0:r1, c0:c1] = ndi.distance_transform_edt(~window, sampling=res) <= radius + 1e-9 * (1.0 + radius)
    return out


def propose_declaration(posterior, detection, *, radius: float) -> Declaration:
    """The declaration the rule would make on ``posterior`` (module docstring).

    Parameters
    ----------
    posterior : (H, W) or (H·W,) array_like
        The robot's posterior, normalised.
    detection : DetectionModel
        Its found regions R(c).
    radius : float, keyword-only
        m, the declared region's reach around R(c*).

    Returns
    -------
    Declaration
    """
    p = np.asarray(posterior, dtype=np.float64).ravel()
    c = int(np.argmax(p))
    mass = float(p[declared_region(detection, c, radius).ravel()].sum())
    return Declaration(c, detection.centres[c].copy(), min(mass, 1.0))


def declaration_error(xy, truth_xy, truth_region=None) -> float:
    """m: distance from the declared point ``xy`` to the true source — to the nearest of the ``truth_region``
    points (the source object's footprint cell centres, (k, 2)) for an object source, to ``truth_xy`` otherwise."""
    xy = np.asarray(xy, dtype=np.float64)
    if truth_region is not None and len(truth_region):
        return float(np.sqrt(((np.asarray(truth_region) - xy) ** 2).sum(axis=1).min()))
    return float(np.linalg.norm(xy - np.asarray(truth_xy, dtype=np.float64)))
