"""Fuzz every public function and constructor with hostile arguments (contract: tests/fuzz/hostile.py).

Each entry gives a valid call; hypothesis spoils one argument at a time — a mutation that must be refused, a
valid alternative form that must give the same result, or an extreme value that must stay clean — and
shrinks a failure to the smallest case.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Callable

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from hostile import (ARRAY_ACCEPT, ARRAY_REFUSE, FLAG_REFUSE, FUZZ, INT_REFUSE, NAMES_REFUSE, OBJECT_REFUSE,
                     SCALAR_EXTREME, SCALAR_REFUSE, Arg, accept_array, clean, finite, record, refuse_array,
                     refused)

import psgsl_pgm as core
from psgsl_pgm import experiment as ex
from psgsl_pgm import networks as nw
from psgsl_pgm import olfaction as olf
from psgsl_pgm import sim


def _dist(rng, shape):
    x = rng.uniform(0.05, 1.0, size=shape)
    return x / x.sum(axis=-1, keepdims=True)


@dataclasses.dataclass
class Entry:
    name: str
    call: Callable[..., Any]
    make: Callable[[], dict]
    args: dict
    out: Callable[[Any], Any] = lambda r: r
    rtol32: float = 2e-3  # results from float32 inputs agree to this

    def __repr__(self) -> str:
        return self.name


def _grid(h=6, w=7):
    occ = np.zeros((h, w), bool)
    occ[0, :] = occ[-1, :] = True
    return occ


R = np.random.default_rng(12)
K = 4
BELIEFS = _dist(R, (3, 5, K))
LIK = np.array([0.4, 0.25, 0.3, 0.05])
PRIOR = np.array([0.3, 0.3, 0.2, 0.2])
OLF = _dist(R, (15,)).reshape(3, 5)
ROOMS = np.array([[0, 1, -1, 0, 1]] * 3)
ROOM_TABLE = _dist(R, (2, K))
GRID = sim.GridMap(_grid(), 0.5, (0.0, 0.0))
GAIN = R.uniform(0, 1, (6, 7))
POSTERIORS = _dist(R, (2, 12)).reshape(2, 3, 4)
PROBLEM_KW = dict(source_likelihood=LIK, background=PRIOR, cells=3, observation_cells=np.array([0, 2]),
                  observation_likelihoods=_dist(R, (2, K)), olfactory_likelihood=np.array([0.2, 0.5, 0.3]),
                  source_prior=np.array([0.2, 0.3, 0.5]), class_names=["oven", "sink", "bed", "tv"],
                  shape=(3,))


def _problem_out(p):
    return p.closed_form_posterior()


ENTRIES = [
    Entry("semantic_source_probability", core.semantic_source_probability,
          lambda: dict(class_probs=BELIEFS, source_likelihood=LIK, class_prior=PRIOR, normalize=True),
          {"class_probs": Arg("dist"), "source_likelihood": Arg("dist"), "class_prior": Arg("dist"),
           "normalize": Arg("flag"), "source_prior": Arg("dist", optional=True)}),
    Entry("update_class_probs", core.update_class_probs,
          lambda: dict(class_probs=BELIEFS, likelihood=_dist(np.random.default_rng(1), (3, 5, K))),
          {"class_probs": Arg("dist"), "likelihood": Arg("prob")}),
    Entry("fuse", lambda a, b, prior=None: core.fuse(a, b, prior=prior),
          lambda: dict(a=OLF, b=_dist(np.random.default_rng(2), (15,)).reshape(3, 5)),
          {"a": Arg("prob", names=("posterior",)), "b": Arg("prob", names=("posterior",)),
           "prior": Arg("prob", optional=True)}),
    Entry("semantic_information_gain", core.semantic_information_gain,
          lambda: dict(class_probs=BELIEFS, source_likelihood=LIK, class_prior=PRIOR, olfactory=OLF,
                       predictive="exact"),
          {"class_probs": Arg("dist"), "source_likelihood": Arg("dist"), "class_prior": Arg("dist"),
           "olfactory": Arg("prob", optional=True)}),
    Entry("room_evidence", core.room_evidence,
          lambda: dict(room_labels=ROOMS, room_class_table=ROOM_TABLE, class_prior=PRIOR),
          {"room_labels": Arg("labels"), "room_class_table": Arg("dist"), "class_prior": Arg("dist")}),
    Entry("field_of_view", core.field_of_view,
          lambda: dict(occupancy=_grid(), pose=np.array([2.5, 2.5, 0.3]), max_range=4.0, half_angle=1.0,
                       min_range=0.0, resolution=1.0, origin=np.array([0.0, 0.0])),
          {"occupancy": Arg("mask"), "pose": Arg("array", float32=False), "max_range": Arg("scalar"),
           "half_angle": Arg("scalar"), "min_range": Arg("scalar"), "resolution": Arg("scalar", names=("extent",)),
           "origin": Arg("array", float32=False)}),
    Entry("view_information_gain", core.view_information_gain,
          lambda: dict(information_gain=GAIN, occupancy=_grid(), pose=np.array([2.5, 2.5, 0.0]),
                       max_range=3.0, half_angle=1.2),
          {"information_gain": Arg("array"), "occupancy": Arg("mask"), "pose": Arg("array", float32=False),
           "max_range": Arg("scalar")}),
    Entry("Ontology", core.Ontology,
          lambda: dict(classes=["oven", "sink", "bed"], gases=["smoke"], source_table=[[0.5, 0.3, 0.1, 0.1]],
                       class_prior=PRIOR, rooms=["kitchen", "bedroom"], room_table=ROOM_TABLE),
          {"classes": Arg("names"), "gases": Arg("names"), "rooms": Arg("names", optional=True),
           "source_table": Arg("dist"), "class_prior": Arg("dist", optional=True),
           "room_table": Arg("dist", optional=True)},
          out=lambda o: o.source_table),
    Entry("Ontology.from_counts", core.Ontology.from_counts,
          lambda: dict(counts={"smoke": {"oven": 3, "sink": 1}}, classes=["oven", "sink", "bed"], concentration=0.5),
          {"concentration": Arg("scalar"), "classes": Arg("names")},
          out=lambda o: o.source_table),
    Entry("SemanticGSLProblem", nw.SemanticGSLProblem, lambda: dict(PROBLEM_KW),
          {"source_likelihood": Arg("dist"), "background": Arg("dist"), "cells": Arg("int"),
           "observation_cells": Arg("labels"), "observation_likelihoods": Arg("prob"),
           "olfactory_likelihood": Arg("prob", optional=True), "source_prior": Arg("dist", optional=True),
           "class_names": Arg("names", names=("class name",), optional=True),
           "shape": Arg("shape", optional=True)},
          out=_problem_out),
    Entry("build_network_a", nw.build_network_a,
          lambda: dict(problem=nw.SemanticGSLProblem(**PROBLEM_KW)), {"problem": Arg("object")},
          out=lambda m: sorted(m.nodes())),
    Entry("GridMap", sim.GridMap, lambda: dict(occupancy=_grid(), resolution=0.5, origin=(1.0, 2.0)),
          {"occupancy": Arg("mask"), "resolution": Arg("scalar"), "origin": Arg("array", float32=False)},
          out=lambda g: (g.occupancy, g.resolution, tuple(g.origin))),
    Entry("box_footprint", sim.box_footprint, lambda: dict(center=np.array([1.0, 2.0]), size=np.array([0.5, 0.4]),
                                                            yaw=0.3),
          {"center": Arg("array", float32=False), "size": Arg("array", float32=False), "yaw": Arg("scalar")}),
    Entry("SceneObject", sim.SceneObject,
          lambda: dict(class_name="oven", footprint=sim.box_footprint((1.0, 1.0), (0.5, 0.5)), z_range=(0.0, 0.9)),
          {"footprint": Arg("array", float32=False), "z_range": Arg("array", float32=False)},
          out=lambda o: o.footprint),
    Entry("segment_mask", sim.segment_mask,
          lambda: dict(grid=GRID, p0=np.array([0.6, 0.8]), p1=np.array([2.9, 2.1]), width=0.3),
          {"grid": Arg("object"), "p0": Arg("array", float32=False), "p1": Arg("array", float32=False),
           "width": Arg("scalar")}),
    Entry("Camera", sim.Camera, lambda: dict(max_range=4.0, half_angle=0.6, min_range=0.2),
          {"max_range": Arg("scalar"), "half_angle": Arg("scalar"), "min_range": Arg("scalar")},
          out=lambda c: (c.max_range, c.half_angle, c.min_range)),
    Entry("GasSensor", sim.GasSensor, lambda: dict(threshold=1.0, window=1.0, noise_std=0.1),
          {"threshold": Arg("scalar"), "window": Arg("scalar"), "noise_std": Arg("scalar")},
          out=lambda g: (g.threshold, g.window, g.noise_std)),
    Entry("FilamentParams", sim.FilamentParams, lambda: dict(dt=0.1, release_rate=10.0, sigma0=0.1),
          {"dt": Arg("scalar"), "release_rate": Arg("scalar"), "sigma0": Arg("scalar")},
          out=lambda p: (p.dt, p.release_rate, p.sigma0)),
    Entry("match_names", sim.match_names, lambda: dict(names=["oven", "bed"], targets=["bed", "sink", "oven"]),
          {"names": Arg("names"), "targets": Arg("names")}),
    Entry("bernoulli", olf.bernoulli, lambda: dict(x=np.array([0.0, 0.5, 3.0])), {"x": Arg("array")}),
    Entry("correlation_length", olf.correlation_length, lambda: dict(diffusivity=0.05, lifetime=20.0, wind_speed=0.2),
          {"diffusivity": Arg("scalar"), "lifetime": Arg("scalar"), "wind_speed": Arg("scalar")}),
    Entry("encounter_scale_mle", olf.encounter_scale_mle,
          lambda: dict(predicted=np.array([0.1, 0.5, 0.9, 0.2]), hits=np.array([False, True, True, False]),
                       false_hit_rate=0.01),
          {"predicted": Arg("prob"), "hits": Arg("mask"), "false_hit_rate": Arg("scalar")}),
    Entry("ExperimentConfig", ex.ExperimentConfig, lambda: dict(warm_up=60.0, speed=0.25, tempering=0.5),
          {"warm_up": Arg("scalar"), "speed": Arg("scalar"), "tempering": Arg("scalar")},
          out=lambda c: c.to_dict()),
    Entry("parse_source", ex.parse_source, lambda: dict(spec=(2.5, 6.0)), {"spec": Arg("array", float32=False,
                                                                                      names=("source",))}),
    Entry("mean_ci", ex.mean_ci, lambda: dict(values=np.array([1.0, 2.5, 2.0]), level=0.95),
          {"values": Arg("array"), "level": Arg("scalar")}),
    Entry("error_and_spread", ex.error_and_spread,
          lambda: dict(posteriors=POSTERIORS, centres=GRID.cell_centres()[:3, :4],
                       truth=np.array([1.0, 1.0])),
          {"posteriors": Arg("prob"), "centres": Arg("array"), "truth": Arg("array", float32=False)}),
]
IDS = [e.name for e in ENTRIES]


def _same(a, b, rtol, what):
    if isinstance(a, dict):
        assert a.keys() == b.keys(), what
        for k in a:
            _same(a[k], b[k], rtol, what)
    elif isinstance(a, (tuple, list)) and not (a and isinstance(a[0], (int, float, np.number))):
        assert len(a) == len(b), what
        for x, y in zip(a, b):
            _same(x, y, rtol, what)
    elif isinstance(a, str) or isinstance(b, str):
        assert a == b, what
    else:
        np.testing.assert_allclose(np.asarray(a, dtype=float), np.asarray(b, dtype=float), rtol=rtol, atol=rtol * 1e-3,
                                   err_msg=what)


def _names(entry, name):
    return (name,) + tuple(entry.args[name].names)


@pytest.mark.parametrize("entry", ENTRIES, ids=IDS)
def test_valid_call_works(entry):
    finite(entry.call(**entry.make()))


def _refusals(arg: Arg, value):
    if arg.kind in ("dist", "prob", "array", "labels"):
        hows = [h for h in ARRAY_REFUSE if not (h == "none" and arg.optional)]
        if arg.kind == "labels":
            hows = [h for h in hows if h not in ("nan", "inf")] + ["float-labels"]
        if arg.kind in ("dist", "prob"):
            hows += ["negative"]
        if arg.kind == "dist":
            hows += ["unnormalised"]
        return hows
    if arg.kind == "mask":
        return ["complex0", "numeric-str", "object-str", "scalar-str", "dict", "nan", "ragged", "bytes", "none",
                "two-and-three"]
    if arg.kind == "scalar":
        return [v for v in SCALAR_REFUSE if not (v is None and arg.optional)]
    if arg.kind == "int":
        return list(INT_REFUSE)
    if arg.kind == "flag":
        return list(FLAG_REFUSE)
    if arg.kind == "names":
        return [v for v in NAMES_REFUSE if not (v is None and arg.optional)]
    if arg.kind == "object":
        return list(OBJECT_REFUSE)
    if arg.kind == "shape":
        return [(2.5,), "3", (True, 3), {"a": 3}, (3.0,), (-3,), (0, 3)]
    raise AssertionError(arg.kind)


def _spoil(arg: Arg, value, how, pos):
    if arg.kind in ("dist", "prob", "array", "labels", "mask") and isinstance(how, str):
        v = np.asarray(value)
        if how == "negative":
            w = v.astype(np.float64).copy()
            w.flat[pos % w.size] = -0.1
            return w
        if how == "unnormalised":
            return np.asarray(value, dtype=np.float64) * 1.5
        if how == "float-labels":
            return v + 0.5
        if how == "two-and-three":
            w = v.astype(np.int64)
            w.flat[pos % w.size] = 2 + pos % 2
            return w
        if how in ("bool",) and v.dtype == bool:
            return v.astype(str)
        return refuse_array(v if v.dtype != bool else v.astype(np.float64), how, pos)
    return how


@pytest.mark.parametrize("entry", ENTRIES, ids=IDS)
@FUZZ
@given(data=st.data())
def test_garbage_is_refused_naming_the_argument(entry, data):
    kwargs = entry.make()
    name = data.draw(st.sampled_from(sorted(entry.args)), label="argument")
    arg = entry.args[name]
    value = kwargs.get(name)
    if value is None and arg.kind in ("dist", "prob", "array"):  # an optional array left out: spoil a valid one
        value = _default_for(entry, name, kwargs)
    how = data.draw(st.sampled_from(_refusals(arg, value)), label="mutation")
    pos = data.draw(st.integers(0, 10**6), label="entry")
    kwargs[name] = _spoil(arg, value, how, pos)
    refused(lambda: entry.call(**kwargs), _names(entry, name), f"{entry.name}({name}={how!r})")


def _default_for(entry, name, kwargs):
    """A valid value for an optional probability argument that the baseline leaves out."""
    ref = {"source_prior": np.full(15, 1 / 15).reshape(3, 5), "prior": np.full((3, 5), 1 / 15),
           "olfactory": np.full((3, 5), 1 / 15)}
    if entry.name == "SemanticGSLProblem" and name == "source_prior":
        return np.array([0.2, 0.3, 0.5])
    return ref[name]


@pytest.mark.parametrize("entry", ENTRIES, ids=IDS)
@FUZZ
@given(data=st.data())
def test_equivalent_valid_forms_give_the_same_result(entry, data):
    kwargs = entry.make()
    base = entry.out(entry.call(**entry.make()))
    arrays = [n for n, a in entry.args.items() if a.kind in ("dist", "prob", "array", "labels", "mask")
              and kwargs.get(n) is not None]
    scalars = [n for n, a in entry.args.items() if a.kind in ("scalar", "int") and kwargs.get(n) is not None]
    names = [n for n, a in entry.args.items() if a.kind == "names" and kwargs.get(n) is not None]
    choices = arrays + scalars + names
    if not choices:
        record("accepted")
        return
    name = data.draw(st.sampled_from(choices), label="argument")
    arg, value = entry.args[name], kwargs[name]
    rtol = 1e-10
    if name in arrays:
        hows = [h for h in ARRAY_ACCEPT if h != "float32" or (arg.float32 and arg.kind in ("dist", "prob", "array"))]
        if arg.kind in ("labels", "mask"):
            hows += ["int32"]
        how = data.draw(st.sampled_from(hows), label="form")
        if how == "int32":
            kwargs[name] = np.asarray(value).astype(np.int32)
        else:
            kwargs[name] = accept_array(np.asarray(value), how)
        rtol = entry.rtol32 if how == "float32" else 1e-10
    elif name in scalars:
        if arg.kind == "int":  # a count: any integer type (a float, even 3.0, is refused by the contract)
            forms = [int(value), np.int64(value), np.int32(value), np.uint16(value)]
        else:
            forms = [np.float64(value), np.float32(value)]
            if float(value) == int(value):
                forms += [int(value), np.int64(int(value))]
        form = data.draw(st.sampled_from(forms), label="form")
        kwargs[name] = form
        rtol = entry.rtol32 if isinstance(form, np.float32) else 1e-10
        how = type(form).__name__
    else:
        how = data.draw(st.sampled_from(["tuple", "list"]), label="form")
        kwargs[name] = tuple(value) if how == "tuple" else list(value)
    try:
        out = entry.out(entry.call(**kwargs))
    except (TypeError, ValueError) as exc:
        raise AssertionError(f"{entry.name}: valid input refused ({name} as {how}): {exc}") from None
    _same(out, base, rtol, f"{entry.name}: {name} as {how} changes the result")
    record("accepted")


@pytest.mark.parametrize("entry", ENTRIES, ids=IDS)
@FUZZ
@given(data=st.data())
def test_extreme_values_stay_clean(entry, data):
    """Accepted with finite results, or refused naming the argument; no other exception, no hang."""
    kwargs = entry.make()
    cands = [n for n, a in entry.args.items() if a.kind in ("scalar", "int", "dist", "prob", "array", "labels")]
    if not cands:
        record("accepted")
        return
    name = data.draw(st.sampled_from(cands), label="argument")
    arg = entry.args[name]
    value = kwargs.get(name)
    if value is None:
        value = _default_for(entry, name, kwargs)
    if arg.kind in ("scalar", "int"):
        kwargs[name] = data.draw(st.sampled_from(SCALAR_EXTREME + (-3, 10**6)), label="value")
    else:
        v = np.asarray(value)
        kind = data.draw(st.sampled_from(["elements", "dtype", "empty"]), label="how")
        if kind == "empty":
            axis = data.draw(st.integers(0, max(v.ndim - 1, 0)), label="axis")
            kwargs[name] = np.take(v, [], axis=axis) if v.ndim else np.zeros(0)
        elif kind == "dtype":
            dtype = data.draw(hnp.floating_dtypes(sizes=(16, 32, 64)) | hnp.integer_dtypes()
                              | hnp.unsigned_integer_dtypes(), label="dtype")
            with np.errstate(all="ignore"):
                kwargs[name] = v.astype(dtype)
        else:
            lo = -1e300 if arg.kind == "array" else 0.0
            elements = st.floats(lo, 1e300, allow_nan=False, allow_infinity=False, allow_subnormal=True)
            if arg.kind == "labels":
                elements = st.integers(-3, 3)
            w = data.draw(hnp.arrays(np.float64 if arg.kind != "labels" else np.int64, v.shape, elements=elements),
                          label="array")
            if arg.kind == "dist":
                with np.errstate(all="ignore"):
                    s = w.sum(axis=-1, keepdims=True)
                    w = np.where(s > 0, w / np.where(s > 0, s, 1.0), w)
            kwargs[name] = w

    def check(out):
        finite(entry.out(out) if out is not None else out)

    clean(lambda: entry.call(**kwargs), _names(entry, name), f"{entry.name}({name}=extreme)", check)
