"""The robot's own models in the experiment: wind from its anemometer, its detector model from reference houses,
its gas hits from its own rule; none of them reads the simulator's wind, detector or sensor parameters."""

import sys

import numpy as np
import pytest

from psgsl_pgm.experiment import ExperimentConfig, VariantPosteriors
from psgsl_pgm.experiment._config import PARAMETER_GRID
from psgsl_pgm.experiment._robot_models import robot_detector_model, robot_hit_rule, wind_basis
from psgsl_pgm.experiment._run import walk
from psgsl_pgm.experiment._tour import exploration_tour
from psgsl_pgm.sim import (HOUSE_CLASSES, Camera, DetectorModel, GasSensor, LocalisationError, MOXSensor, PIDSensor,
                           make_world)


class _SimulatorOnlyWind:
    """The world's wind, readable only from the simulator's own modules (psgsl_pgm.sim.*)."""

    def __init__(self, wind):
        object.__setattr__(self, "_wind", wind)

    def __getattr__(self, name):
        caller = sys._getframe(1).f_globals.get("__name__", "")
        if not caller.startswith("psgsl_pgm.sim"):
            raise RuntimeError(f"{caller} read the simulator's wind field (.{name})")
        return getattr(object.__getattribute__(self, "_wind"), name)


def guard_true_pose(world, allow=None):
    """``world`` with its true pose, its localisation offset and the error's parameters readable only from the
    simulator's own modules (psgsl_pgm.sim.*), or from the frames ``allow(frame)`` accepts."""
    cls = type(world)

    def check(name):
        frame = sys._getframe(2)  # the code that reads the attribute
        caller = frame.f_globals.get("__name__", "")
        if not (caller.startswith("psgsl_pgm.sim") or (allow is not None and allow(frame))):
            raise RuntimeError(f"{caller} read the robot's true pose (.{name})")

    ns = {}
    for name in ("true_positions", "_offset_at", "_pull_back"):
        ns[name] = property(lambda self, n=name, fn=getattr(cls, name): (check(n), fn.__get__(self))[1])
    for name in ("localisation", "_offsets", "_rng_pose"):
        key = "_guarded_" + name
        world.__dict__[key] = world.__dict__.pop(name)
        ns[name] = property(lambda self, n=name, k=key: (check(n), self.__dict__[k])[1],
                            lambda self, v, k=key: self.__dict__.__setitem__(k, v))
    world.__class__ = type(f"TruePoseGuarded{cls.__name__}", (cls,), ns)
    return world


class _SimulatorOnlyDetector:
    """The world's detector: its label vocabulary (classes, labels, nothing) is public, every other attribute (the
    confusion, the detection curve, the persistence, the distractors) readable only from psgsl_pgm.sim.*."""

    VOCABULARY = ("classes", "labels", "nothing")

    def __init__(self, detector):
        object.__setattr__(self, "_detector", detector)

    def __getattr__(self, name):
        caller = sys._getframe(1).f_globals.get("__name__", "")
        if name not in self.VOCABULARY and not caller.startswith("psgsl_pgm.sim"):
            raise RuntimeError(f"{caller} read the simulator's detector parameters (.{name})")
        return getattr(object.__getattribute__(self, "_detector"), name)


@pytest.fixture(scope="module")
def guarded_world():
    world = make_world(seed=3, source="oven", warm_up=20.0)
    world.wind = _SimulatorOnlyWind(world.wind)
    return world


def test_the_guard_catches_a_read_of_the_wind_field(guarded_world):
    with pytest.raises(RuntimeError, match="read the simulator's wind field"):
        guarded_world.wind.mean()


@pytest.mark.parametrize("estimator", ["infotaxis", "analytic-plume"])
def test_no_estimator_code_path_reads_the_simulated_wind(guarded_world, estimator):
    config = ExperimentConfig(stops=12)
    beliefs = VariantPosteriors(guarded_world, estimator, config)
    tour = exploration_tour(guarded_world.house).first(12)
    for _, stop, reading, wind, frames in walk(guarded_world, tour, config):
        beliefs.observe(stop, reading, wind, frames)
        beliefs.posteriors()
        beliefs.estimator.information_gain([stop])
    assert beliefs.wind.n_readings == 12
    # re-solved at readings 1, 2, 4, 8 at most (and once for the still-air start)
    assert 2 <= beliefs.n_wind_solves <= 5


@pytest.fixture(scope="module")
def pose_guarded_world():
    """A robot with a localisation error whose true pose, offset and error parameters only the simulator reads."""
    world = make_world(seed=3, source="oven", warm_up=20.0, localisation=LocalisationError())
    world.wind = _SimulatorOnlyWind(world.wind)
    return guard_true_pose(world)


def test_the_guard_catches_a_read_of_the_true_pose(pose_guarded_world):
    for read in (lambda w: w.true_positions((3.0, 6.0)), lambda w: w._offset_at(0.0), lambda w: w._offsets,
                 lambda w: w.localisation.sigma, lambda w: w._rng_pose):
        with pytest.raises(RuntimeError, match="read the robot's true pose"):
            read(pose_guarded_world)


@pytest.mark.parametrize("estimator", ["infotaxis", "analytic-plume"])
def test_no_robot_code_path_reads_the_true_pose(pose_guarded_world, estimator):
    """The readings, frames and beliefs of a tour with a localisation error: the world applies the offset, the
    robot's code sees believed poses only."""
    config = ExperimentConfig(stops=8)
    beliefs = VariantPosteriors(pose_guarded_world, estimator, config)
    tour = exploration_tour(pose_guarded_world.house).first(8)
    for _, stop, reading, wind, frames in walk(pose_guarded_world, tour, config):
        beliefs.observe(stop, reading, wind, frames)
        beliefs.posteriors()
        beliefs.estimator.information_gain([stop])
        assert all(np.array_equal(f.pose[:2], stop) for f in frames)  # the frames carry the believed pose
    assert beliefs.wind.n_readings == 8


def test_no_robot_code_path_reads_the_detector_parameters():
    """A realistic camera and detector (furniture occlusion, range and bearing fall-off, persistent instance
    labels, distractor sites) in the world, guarded: the experiment reads its frames with the detector model
    counted on reference houses, and no code outside the simulator reads the world's detector parameters."""
    world = make_world(seed=3, source="oven", warm_up=5.0, camera=Camera(occlusion="furniture"),
                       detector=DetectorModel.realistic(HOUSE_CLASSES))
    world.detector = _SimulatorOnlyDetector(world.detector)
    with pytest.raises(RuntimeError, match="read the simulator's detector parameters"):
        world.detector.confusion
    config = ExperimentConfig(stops=6)
    beliefs = VariantPosteriors(world, "analytic-plume", config)
    robot = beliefs.detector_model
    assert isinstance(robot, DetectorModel) and robot is robot_detector_model(HOUSE_CLASSES)
    assert robot.half_range is None and robot.persistence == 0 and robot.distractors == 0  # its own model
    tour = exploration_tour(world.house).first(6)
    n_frames = 0
    for _, stop, reading, wind, frames in walk(world, tour, config):
        assert all(f.bearing is not None for f in frames)  # made by the realistic detector
        beliefs.observe(stop, reading, wind, frames)
        beliefs.posteriors()
        n_frames += len(frames)
    assert n_frames >= 6
    assert np.isfinite(beliefs.maps["semantics"].probs).all()


def test_wind_estimate_finds_the_through_flow_of_a_house():
    """The house's mean flow is the inlet→outlet potential flow at 0.2 m/s mean speed plus the time-mean of the
    eddies: after a whole tour the coefficient of the unit-speed basis is the through-flow speed to ±15 %."""
    world = make_world(seed=5, source="oven", warm_up=10.0)
    config = ExperimentConfig()
    beliefs = VariantPosteriors(world, "analytic-plume", config)
    for _, stop, reading, wind, _ in walk(world, exploration_tour(world.house), config, camera=False):
        beliefs.wind.add(stop, wind)
    a = beliefs.wind.coefficients
    assert a.shape == (1,) and a[0] == pytest.approx(0.2, rel=0.15)
    truth = world.wind.mean().velocity  # the test, not the estimator, may read the truth
    free = world.house.grid.free
    est = beliefs.wind.field()
    assert np.linalg.norm((est - truth)[free]) < 0.6 * np.linalg.norm(truth[free])


def test_wind_basis_without_windows_is_the_two_uniform_flows():
    world = make_world(seed=0, warm_up=0.0)
    house = world.house
    house_no_windows = type("H", (), {"grid": house.grid, "inlet": np.zeros_like(house.inlet),
                                      "outlet": house.outlet})()
    b = wind_basis(house_no_windows)
    assert b.shape == (2,) + house.shape + (2,)
    assert (b[0, ..., 0] == house.grid.free).all() and (b[1, ..., 1] == house.grid.free).all()
    assert not b[0, ..., 1].any() and not b[1, ..., 0].any()


def test_detector_estimate_converges_to_the_true_confusion_matrix():
    rng = np.random.default_rng(0)
    true = DetectorModel.default(HOUSE_CLASSES, p_max=0.8, near=1.5, scale=2.0, false_positive=0.05)
    k = len(true.classes)
    n = 400_000
    c = rng.integers(0, k, n)
    d = rng.uniform(0.2, 6.0, n)
    z = true.sample(c, d, rng)
    est = DetectorModel.from_counts(true.classes, c, z, d, pseudo_count=1.0)
    # every entry within 5 binomial standard errors of its row's detections (≈ n / k · p_d each)
    det = z != true.nothing
    n_row = np.bincount(c[det], minlength=k)
    se = np.sqrt(true.confusion * (1 - true.confusion) / n_row[:, None]) + 1.0 / n_row[:, None]
    assert (np.abs(est.confusion - true.confusion) < 5 * se).all()
    assert est.p_max == pytest.approx(0.8, abs=0.01)
    assert est.near == pytest.approx(1.5, abs=0.1)
    assert est.scale == pytest.approx(2.0, rel=0.05)
    assert est.false_positive == pytest.approx(0.05, abs=0.003)
    with pytest.raises(ValueError, match="must lie in"):
        DetectorModel.from_counts(true.classes, c[:5], z[:5] + k, d[:5])


def test_frames_are_read_with_the_robot_detector_model():
    world = make_world(seed=4, source="oven", warm_up=5.0)
    config = ExperimentConfig(stops=3)
    beliefs = VariantPosteriors(world, "analytic-plume", config)
    robot = robot_detector_model()
    assert beliefs.detector_model is robot and robot is not world.detector
    assert not np.array_equal(robot.confusion, world.detector.confusion)
    twin = VariantPosteriors(world, "analytic-plume", ExperimentConfig(stops=3, detector_model="simulator"))
    assert twin.detector_model is None
    frame = world.camera_frame((2.0, 6.0, 0.0))
    beliefs.observe((2.0, 6.0), world.sense_gas((2.0, 6.0)), world.sense_wind((2.0, 6.0)), [frame])
    reread = robot.likelihood(frame.labels, frame.distance)
    from psgsl_pgm.core._class_beliefs import ClassBeliefMap
    ref = ClassBeliefMap.from_prior(world.house.shape, beliefs.class_prior, world.detector.classes)
    ref._apply(frame.cells, reread, None)
    np.testing.assert_allclose(beliefs.maps["semantics"].probs, ref.probs, rtol=1e-12)
    with pytest.raises(ValueError, match="detector_model must be one of"):
        ExperimentConfig(detector_model="true")


def test_both_estimators_get_the_calibrated_inputs():
    from psgsl_pgm.experiment._step import make_estimator
    from psgsl_pgm.olfaction import PlumeModel

    cfg = ExperimentConfig(pmfs_tempering=0.37, tempering=0.29)
    model = PlumeModel(np.zeros((6, 8), bool), resolution=0.25, diffusivity=cfg.diffusivity, lifetime=cfg.lifetime,
                       encounter_scale=cfg.encounter_scale)
    assert make_estimator("analytic-plume", model, cfg).tempering == 0.37
    assert make_estimator("infotaxis", model, cfg).tempering == 0.29
    world = make_world(seed=6, source="oven", warm_up=5.0)
    for name in ("infotaxis", "analytic-plume"):
        b = VariantPosteriors(world, name, cfg)
        assert (b.model.diffusivity, b.model.lifetime, b.model.encounter_scale) == (
            cfg.diffusivity, cfg.lifetime, cfg.encounter_scale)
        assert not b.model.wind.any()  # still air until the first anemometer reading


def test_infotaxis_gets_the_parameter_grid_and_the_plume_solves_follow_the_wind():
    """The grid Infotaxis estimator marginalises over config.parameter_grid (its weights normalised); PMFS keeps
    the single (D, τ, κ); a re-solved wind re-solves every component's plume (all carry the estimated wind)."""
    from psgsl_pgm.experiment._step import make_estimator
    from psgsl_pgm.olfaction import PlumeModel

    grid = ((0.02, 100.0, 0.5, 1.0), (0.0131, 284.0, 0.821, 3.0))
    cfg = ExperimentConfig(parameter_grid=grid, stops=6)
    model = PlumeModel(np.zeros((6, 8), bool), resolution=0.25, diffusivity=cfg.diffusivity, lifetime=cfg.lifetime,
                       encounter_scale=cfg.encounter_scale)
    est = make_estimator("infotaxis", model, cfg)
    np.testing.assert_array_equal(est.parameter_grid, [[0.02, 100.0, 0.5, 0.25], [0.0131, 284.0, 0.821, 0.75]])
    assert est.n_components == 2 and est.plume_models[1] is model  # the config's own (D, τ) shares the model
    assert not hasattr(make_estimator("analytic-plume", model, cfg), "parameter_grid")
    assert ExperimentConfig(parameter_grid=None).parameter_grid is None
    assert ExperimentConfig().parameter_grid is None and "parameter_grid" not in ExperimentConfig().to_dict()
    with_grid = ExperimentConfig(parameter_grid=PARAMETER_GRID)
    assert with_grid.to_dict()["parameter_grid"] == [list(r) for r in PARAMETER_GRID]
    world = make_world(seed=6, source="oven", warm_up=5.0)
    b = VariantPosteriors(world, "infotaxis", cfg)
    stop = exploration_tour(world.house).stops[0]
    b.observe(stop, world.sense_gas(stop), world.sense_wind(stop), [])
    assert b.n_wind_solves == 2 and b.estimator.model is b.model
    assert all(np.array_equal(m.wind, b.model.wind) and m.wind.any() for m in b.estimator.plume_models)
    with pytest.raises(ValueError, match="parameter_grid must be"):
        ExperimentConfig(parameter_grid=((0.01, 100.0, 0.5),))
    with pytest.raises(ValueError, match="non-negative weights"):
        ExperimentConfig(parameter_grid=((0.01, 100.0, 0.5, -1.0),))


def test_the_robot_can_calibrate_on_reference_frames_of_a_realistic_detector():
    """Counted on reference houses seen by a realistic camera and detector: the per-cell estimate absorbs the
    cos⁴ bearing loss into its p_max (mean of cos⁴ over the ±35° opening ≈ 0.75, so p_max ≈ 0.9 · 0.75 near by)
    and the distractor sites into its false-positive rate (above the realistic detector's 0.01 per cell)."""
    robot = robot_detector_model(realistic=True)
    assert isinstance(robot, DetectorModel) and robot is not robot_detector_model()
    assert robot.half_range is None and robot.angle_power == 0 and not robot.correlated
    beta = np.linspace(-np.deg2rad(35), np.deg2rad(35), 10_001)
    assert robot.p_max == pytest.approx(0.9 * np.mean(np.cos(beta) ** 4), abs=0.05)
    assert robot.false_positive > 0.01
    with pytest.raises(TypeError, match="realistic must be True or False"):
        robot_detector_model(realistic="yes")


# ---- gas hits: the robot's rule for its kind of sensor, never the sensor's parameters -----------------------------
class _SimulatorOnlyMOX(MOXSensor):
    """A MOX sensor whose parameters only the simulator's own modules may read (its class stays visible: the
    robot knows which kind of sensor it carries). ``allowed`` names what robot-side code may read."""

    allowed: frozenset = frozenset()

    def __getattribute__(self, name):
        if not name.startswith("__") and name != "allowed":
            caller = sys._getframe(1).f_globals.get("__name__", "")
            if not caller.startswith("psgsl_pgm.sim") and name not in type(self).allowed:
                raise RuntimeError(f"{caller} read the gas sensor's .{name}")
        return object.__getattribute__(self, name)


class _LoopMOX(_SimulatorOnlyMOX):
    # the closed loop plans with the time it stands at a stop to read (its sampling window, a robot setting);
    # nothing that characterises the sensing element
    allowed = frozenset({"window"})


def test_the_sensor_guard_catches_a_read_of_its_parameters():
    s = _SimulatorOnlyMOX()
    with pytest.raises(RuntimeError, match=r"read the gas sensor's \.recovery_time"):
        s.recovery_time
    with pytest.raises(RuntimeError, match=r"read the gas sensor's \.read"):
        s.read([1.0] * 10, 0.1, rng=np.random.default_rng(0))
    assert isinstance(s, MOXSensor) and robot_hit_rule(s).kind == "rise"  # its kind, not its parameters


def test_the_fixed_tour_decides_mox_hits_without_reading_the_sensor():
    world = make_world(seed=0, source="oven", warm_up=60.0, gas_sensor=_SimulatorOnlyMOX())
    config = ExperimentConfig()
    beliefs = VariantPosteriors(world, "infotaxis", config)
    tour = exploration_tour(world.house).first(100)
    hits = []
    for _, stop, reading, wind, frames in walk(world, tour, config, camera=False):
        beliefs.observe(stop, reading, wind, frames)
        hits.append(reading.hit)
    assert all(isinstance(h, bool) for h in hits)
    assert 5 <= sum(hits) <= 30  # this tour meets the oven's plume (18 hits over the whole tour)
    assert beliefs.estimator.posterior.sum() == pytest.approx(1.0)


def test_the_closed_loop_runs_with_a_mox_sensor_without_reading_its_parameters():
    from psgsl_pgm.search import SearchConfig, run_closed_loop

    world = make_world(seed=1, source="oven", warm_up=60.0, gas_sensor=_LoopMOX())
    run = run_closed_loop("oven", 1, "infotaxis", "semantics+rooms", world=world,
                          search=SearchConfig(time_budget=60.0))
    assert run.hit.dtype == bool and len(run.hit) >= 2 and np.isfinite(run.error).all()


def test_the_experiment_runs_with_mox_and_pid_sensors_from_make_world():
    from psgsl_pgm.experiment import run_search

    for sensor in (MOXSensor(), PIDSensor()):
        world = make_world(seed=2, source="oven", warm_up=30.0, gas_sensor=sensor)
        run = run_search("oven", 2, "analytic-plume", config=ExperimentConfig(stops=10), world=world)
        assert run.hit.dtype == bool and run.n_steps == 10 and np.isfinite(run.error).all()


def test_mox_hits_are_the_rise_rule_on_the_readings_and_the_ideal_sensors_are_its_own():
    """The tour's MOX hits are HitRule("rise") applied to the raw readings; the ideal sensor's hits are exactly
    value >= threshold, the reading passed through untouched (the golden episodes rest on this)."""
    from psgsl_pgm.experiment._step import visit
    from psgsl_pgm.olfaction import HitRule

    config = ExperimentConfig()
    assert robot_hit_rule(GasSensor()) is None
    assert robot_hit_rule(MOXSensor()).kind == "rise" and robot_hit_rule(PIDSensor()).kind == "level"
    world = make_world(seed=0, source="oven", warm_up=60.0)
    tour = exploration_tour(world.house).first(100)
    readings = [r for _, _, r, _, _ in walk(world, tour, config, camera=False)]
    assert all(r.trace is None and r.hit == (r.value >= 1.0) for r in readings)
    assert sum(r.hit for r in readings) > 5
    mox = make_world(seed=0, source="oven", warm_up=60.0, gas_sensor=MOXSensor())
    raw = []
    for j, stop in enumerate(tour.stops):  # the walk's own steps, without a rule
        drive = float(np.linalg.norm(stop - tour.stops[j - 1])) if j else 0.0
        if drive:
            mox.advance(drive / config.speed)
        raw.append(mox.sense_gas(stop))
        mox.sense_wind(stop)
    twin = make_world(seed=0, source="oven", warm_up=60.0, gas_sensor=MOXSensor())
    walked = [r for _, _, r, _, _ in walk(twin, tour, config, camera=False)]
    rule = HitRule("rise")
    assert [rule.decide(r.trace) for r in raw] == [r.hit for r in walked]
    with pytest.raises(ValueError, match="leaves the hit decision to the robot"):
        visit(make_world(seed=0, warm_up=0.0, gas_sensor=MOXSensor()), tour.stops[0], tour.headings[0], config,
              camera=False)


def test_recording_a_world_whose_hits_the_robot_decides_is_refused_before_anything_is_written():
    from psgsl_pgm.experiment._record import EpisodeRecorder

    world = make_world(seed=0, warm_up=0.0, gas_sensor=MOXSensor())
    with pytest.raises(ValueError, match="--record needs the world's thresholded GasSensor, got a MOXSensor"):
        EpisodeRecorder().watch(world)
