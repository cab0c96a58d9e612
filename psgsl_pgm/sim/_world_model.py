"""World models: which parts of the simulated world follow the robot's own assumptions, and which do not.

The ``ideal`` world is built from the same models the robot's estimators assume: potential-flow wind between the
windows, an instantaneous noiseless gas sensor read as hits at a threshold, a camera whose labelling errors are
independent per cell and frame and that sees over furniture, and a robot that knows exactly where it is. Results
measured there say how well the method works when its assumptions hold.

The ``realistic`` world breaks each assumption with a model taken from outside the robot's code:

============  ==========================================================================================
component     what changes
============  ==========================================================================================
``cfd-wind``  wind from a lattice Boltzmann CFD solve of the house (lbmpy): walls and tall furniture are
              obstacles, the windows inlets and outlets (:func:`cfd_wind`; the ``cfd`` extra); the filaments
              go round the same furniture, and a source inside it releases where its object meets the air
``mox``       a metal-oxide gas sensor with slow rise and slower recovery, noise and baseline drift
              (:class:`MOXSensor`), an anemometer with a datasheet's noise and offset
              (:meth:`Anemometer.datasheet`); the robot decides hits from the sensor's response
``camera``    occlusion by walls and furniture, detection that falls with range and viewing angle, labelling
              errors that persist per object and false positives that recur at the same places
              (``Camera(occlusion="furniture")``, :meth:`DetectorModel.realistic`); a close-range source
              detector that misses one pass in five (:meth:`SourceDetector.realistic`)
``pose``      localisation error: a bounded drift between where the robot is and where it believes it is
              (:class:`LocalisationError`); the robot plans and fuses in its believed frame
============  ==========================================================================================

A model is named ``ideal``, ``realistic``, or ``ideal+`` one or more components (``ideal+mox``,
``ideal+camera+pose``): each assumption can be switched off alone to measure what it costs.
"""

from __future__ import annotations

from dataclasses import dataclass

from .._shared._validate import did_you_mean

__all__ = ["WORLD_COMPONENTS", "WORLD_MODELS", "WorldModel"]

#: The presets.
WORLD_MODELS = ("ideal", "realistic")

#: The parts of the world that ``realistic`` replaces, in the order names are written.
WORLD_COMPONENTS = ("cfd-wind", "mox", "camera", "pose")

#: The CFD solve of a house is one per house (not per episode): its gusts are seeded by this constant, so that
#: every episode, policy and condition of a house shares one cached flow; episodes differ in the filaments' noise,
#: the sensors' noise and the camera's draws.
CFD_SEED = 0

#: Seconds of CFD wind before the snapshots loop.
CFD_DURATION = 600.0


@dataclass(frozen=True)
class WorldModel:
    """Which assumptions of the robot the simulated world breaks (see the module docstring).

    Parameters
    ----------
    components : tuple of str
        A subset of :data:`WORLD_COMPONENTS` (any order; stored in that order). Empty: the ideal world.

    Examples
    --------
    >>> WorldModel.parse("realistic").components
    ('cfd-wind', 'mox', 'camera', 'pose')
    >>> WorldModel.parse("ideal+pose+mox").name
    'ideal+mox+pose'
    >>> WorldModel.parse("ideal").name
    'ideal'
    """

    components: tuple = ()

    def __post_init__(self):
        if isinstance(self.components, str) or not all(isinstance(c, str) for c in self.components):
            raise TypeError(f"components must be a tuple of names from {WORLD_COMPONENTS}, got {self.components!r}")
        unknown = [c for c in self.components if c not in WORLD_COMPONENTS]
        if unknown:
            raise ValueError(f"unknown world component {unknown[0]!r}{did_you_mean(unknown[0], WORLD_COMPONENTS)}; "
                             f"the components are {', '.join(WORLD_COMPONENTS)}")
        object.__setattr__(self, "components", tuple(c for c in WORLD_COMPONENTS if c in self.components))

    @classmethod
    def parse(cls, name) -> WorldModel:
        """The model named ``ideal``, ``realistic`` or ``ideal+<component>[+<component>…]``."""
        if isinstance(name, WorldModel):
            return name
        if not isinstance(name, str):
            raise TypeError(f"a world model must be a name (str), got {type(name).__name__}")
        text = name.strip().lower()
        if text == "realistic":
            return cls(WORLD_COMPONENTS)
        head, *parts = text.split("+")
        if head != "ideal":
            expected = "ideal, realistic, or ideal+COMPONENT[+COMPONENT...] with components " \
                       + ", ".join(WORLD_COMPONENTS)
            raise ValueError(f"unknown world model {name!r}{did_you_mean(head, WORLD_MODELS)}; expected {expected}")
        if len(set(parts)) != len(parts):
            raise ValueError(f"world model {name!r} names a component twice")
        return cls(tuple(parts))

    @property
    def name(self) -> str:
        """``ideal``, ``realistic`` or ``ideal+…`` (the canonical spelling)."""
        if not self.components:
            return "ideal"
        if self.components == WORLD_COMPONENTS:
            return "realistic"
        return "+".join(("ideal",) + self.components)

    def __contains__(self, component) -> bool:
        return component in self.components

    def check_available(self) -> None:
        """Raise :class:`ImportError` (one line: what to install) when a component's solver is missing: the CFD
        wind needs lbmpy (the ``cfd`` extra) and a C compiler. A command checks this before it writes anything."""
        if "cfd-wind" in self:
            from ._lbm import _check_compiler, _lbmpy

            _lbmpy()
            _check_compiler()

    def source_detector(self):
        """The close-range source detector of this model's worlds (:class:`SourceDetector`): the realistic one
        with the ``camera`` component, one that never misses otherwise."""
        from ._source_detector import SourceDetector

        return SourceDetector.realistic() if "camera" in self else SourceDetector()

    def world_kwargs(self, house, *, wind_speed: float = 0.2, cfd_cache=None) -> dict:
        """Keyword arguments of :func:`psgsl_pgm.sim.make_world` that build this model's parts for ``house``.

        Parameters
        ----------
        house : House
        wind_speed : float, keyword-only
            The inlet speed of the CFD wind, m/s (the world's ``wind.speed``).
        cfd_cache : path-like, optional, keyword-only
            Where the CFD flows are kept (default: :func:`cfd_wind`'s).

        Returns
        -------
        dict
            Empty for the ideal world: ``make_world``'s defaults are the ideal parts.
        """
        kwargs = {}
        if "cfd-wind" in self:
            from ._lbm import cfd_wind

            from ._lbm import cfd_obstacles

            kwargs["wind"] = cfd_wind(house, speed=wind_speed, duration=CFD_DURATION, seed=CFD_SEED,
                                      cache_dir=cfd_cache)
            kwargs["gas_obstacles"] = cfd_obstacles(house)  # the gas goes round what the flow goes round
        if "mox" in self:
            from ._mox import MOXSensor
            from ._sensors import Anemometer

            kwargs["gas_sensor"] = MOXSensor()
            kwargs["anemometer"] = Anemometer.datasheet()
        if "camera" in self:
            from ._camera import Camera
            from ._detector import DetectorModel

            kwargs["camera"] = Camera(occlusion="furniture")
            kwargs["detector"] = DetectorModel.realistic(house.classes)
            kwargs["source_detector"] = self.source_detector()
        if "pose" in self:
            from ._pose import LocalisationError

            kwargs["localisation"] = LocalisationError()
        return kwargs
