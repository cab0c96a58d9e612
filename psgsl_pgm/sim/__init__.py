"""A simulated house for the validation experiment (paper Sec. "Validation"), without GADEN/Unity/Voxeland.

Lightweight, seeded, vectorised substitutes for the lab's tool chain:

* environments — :class:`GridMap` (the core's ``psgsl_pgm.GridMap``), ROS ``map_server`` maps (:func:`load_ros_map`), room-category maps
  (:func:`load_room_map`), object lists (:func:`load_objects`), and the embedded :func:`default_house`;
* wind — potential flow between inlet and outlet windows with a slow divergence-free perturbation
  (:func:`potential_flow`, :func:`make_wind`), a GADEN CFD export (:func:`read_gaden_wind_csv`, written by
  :func:`write_gaden_wind_csv`), or time-resolved lattice Boltzmann CFD through the house (:func:`cfd_wind`, the
  ``cfd`` extra);
* gas — GADEN's filament model in 2-D (:class:`FilamentModel`), gas sensors (the ideal :class:`GasSensor`, a
  metal-oxide :class:`MOXSensor`, a photo-ionisation :class:`PIDSensor`), the :class:`Anemometer` and an
  electronic nose that names the gas (:class:`ElectronicNose`);
* vision — camera field of view, a detector with distance-dependent detection and class confusion
  (:class:`DetectorModel`), frames (:func:`take_frame`) and the dense class-belief map (:class:`SemanticMap`);
* :func:`make_world` — all of it on one clock for the experiment, optionally with the robot's localisation
  error (:class:`LocalisationError`);
* :class:`WorldModel` — the ``ideal`` world (built from the robot's own assumptions) or the ``realistic`` one (CFD
  wind, a MOX sensor, an occluding camera with persistent errors, localisation error), one component at a time;
* :func:`generate_house` — generated homes (3–8 typed rooms, doors, windows, furniture per room type, wind),
  each a world that can be written as a world file, with their ontology :func:`generated_ontology`;
* :func:`load_world` — a user's house from a world file (map, rooms, objects, ontology, wind, sources); the
  embedded house is the world :func:`default_world`;
* drawing — the package's one map plotter: :func:`plot_house`, :func:`plot_cell_map` (a value per cell with
  its colour bar) and :func:`map_norm` (one colour scale across compared panels); matplotlib on call only.

Modelling choice: walls block wind, gas, the camera and the robot; furniture is low, so wind, gas and the
camera pass over it, but the robot must avoid it (:attr:`House.robot_obstacles`).
"""

from ..geometry._grid import GridMap  # the core's grid (psgsl_pgm.GridMap), re-exported for simulator users
from ..geometry._sight import LineOfSightCache, cells_clear  # the core's one line-of-sight rule
from ._camera import OCCLUSIONS, Camera, Frame, take_frame
from ._cfd import read_gaden_wind_csv, read_gaden_wind_snapshots, write_gaden_wind_csv
from ._classes import HOUSE_CLASSES, HOUSE_ROOMS, OTHER, match_names, reindex
from ._detector import DEFAULT_CONFUSION_GROUPS, NOTHING, DetectorErrors, DetectorModel
from ._enose import ENOSE_GASES, ENOSE_SENSORS, ElectronicNose, Smell, draw_gas
from ._filaments import FilamentModel, FilamentParams, read_gaden_config
from ._generate import AREA_RANGE, ROOM_RANGE, GeneratedHouse, generate_house
from ._generated_ontology import GENERATOR_REFERENCE_SEEDS, generated_ontology
from ._house import House, default_house, segment_mask
from ._lbm import cfd_wind
from ._objects import SceneObject, box_footprint, load_objects, save_objects
from ._plot import figure_problems, map_norm, plot_cell_map, plot_house
from ._pose import LocalisationError
from ._source_detector import SourceDetector
from ._roommap import load_room_map, save_room_map
from ._rosmap import load_ros_map, save_ros_map
from ._semantic_map import SemanticMap
from ._mox import MOXSensor, MOXState, PIDSensor
from ._sensors import Anemometer, GasReading, GasSensor
from ._wind import WindField, WindSequence, make_wind, potential_flow
from ._world import World, make_world
from ._world_model import WORLD_COMPONENTS, WORLD_MODELS, WorldModel
from ._worldfile import (MAX_FREE_CELLS, MAX_WIND_SPEED, WorldSpec, check_free_cells, default_world, load_world,
                         navigable)

__all__ = [
    "AREA_RANGE",
    "Anemometer",
    "Camera",
    "DEFAULT_CONFUSION_GROUPS",
    "DetectorErrors",
    "DetectorModel",
    "ENOSE_GASES",
    "ENOSE_SENSORS",
    "ElectronicNose",
    "FilamentModel",
    "FilamentParams",
    "Frame",
    "GENERATOR_REFERENCE_SEEDS",
    "GeneratedHouse",
    "GasReading",
    "GasSensor",
    "GridMap",
    "HOUSE_CLASSES",
    "HOUSE_ROOMS",
    "House",
    "LineOfSightCache",
    "LocalisationError",
    "SourceDetector",
    "MOXSensor",
    "MOXState",
    "NOTHING",
    "OCCLUSIONS",
    "OTHER",
    "PIDSensor",
    "ROOM_RANGE",
    "SceneObject",
    "SemanticMap",
    "Smell",
    "WindField",
    "WindSequence",
    "WORLD_COMPONENTS",
    "WORLD_MODELS",
    "World",
    "WorldModel",
    "WorldSpec",
    "MAX_FREE_CELLS",
    "MAX_WIND_SPEED",
    "check_free_cells",
    "box_footprint",
    "cfd_wind",
    "cells_clear",
    "default_house",
    "default_world",
    "draw_gas",
    "figure_problems",
    "generate_house",
    "generated_ontology",
    "load_objects",
    "load_world",
    "load_ros_map",
    "load_room_map",
    "make_wind",
    "make_world",
    "map_norm",
    "match_names",
    "navigable",
    "plot_cell_map",
    "plot_house",
    "potential_flow",
    "read_gaden_config",
    "read_gaden_wind_csv",
    "read_gaden_wind_snapshots",
    "reindex",
    "save_objects",
    "save_ros_map",
    "save_room_map",
    "segment_mask",
    "take_frame",
    "write_gaden_wind_csv",
]
