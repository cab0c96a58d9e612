"""The closed-loop search as a gymnasium environment (the ``gym`` extra).

``import psgsl_pgm.gym`` registers ``psgsl/House-v0`` (:class:`HouseEnv`); nothing else in the package imports
gymnasium.

Examples
--------
>>> import gymnasium
>>> import psgsl_pgm.gym
>>> "psgsl/House-v0" in gymnasium.registry
True
"""

try:
    import gymnasium
except ImportError as exc:  # the extra is missing: one line naming it
    raise ImportError("psgsl_pgm.gym needs gymnasium: pip install 'psgsl-pgm[gym]'") from exc

from ._env import WORLDS, HouseEnv
from ._features import CANDIDATE_FEATURES, candidate_table, downsample_belief

__all__ = ["CANDIDATE_FEATURES", "ENV_ID", "HouseEnv", "WORLDS", "candidate_table", "downsample_belief"]

#: The environment's id in gymnasium's registry.
ENV_ID = "psgsl/House-v0"

if ENV_ID not in gymnasium.registry:
    gymnasium.register(id=ENV_ID, entry_point="psgsl_pgm.gym._env:HouseEnv")
