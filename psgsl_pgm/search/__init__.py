"""Closed-loop search: policies that choose where to go and where to look with φ(p) = φ_G(p) + φ_O(p)
(Sec. "Information Gain Optimization"), and the open-space benchmark of the literature."""

from ._open_space import OPEN_SPACE_POLICIES, OpenSpaceSearch, grid_size, hit_probability, open_space_benchmark

__all__ = ["OPEN_SPACE_POLICIES", "OpenSpaceSearch", "grid_size", "hit_probability", "open_space_benchmark"]
