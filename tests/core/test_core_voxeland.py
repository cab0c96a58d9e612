"""The column weights of a Voxeland map in bounded memory equal the dense voxel map's semantic term."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from psgsl_pgm import semantic_source_probability
from psgsl_pgm.core._voxeland import voxeland_column_weights
from psgsl_pgm.geometry import GridMap
from psgsl_pgm.io._class_maps import voxeland_class_beliefs

CLASSES = ("oven", "microwave", "sink", "other")
PRIOR = np.array([0.05, 0.05, 0.1, 0.8])
LIKELIHOOD = np.array([[0.6, 0.3, 0.0, 0.1], [0.0, 0.0, 0.9, 0.1]])  # two gases
HOUSE_B = Path(__file__).resolve().parents[3] / "shared" / "data" / "mapir_house_B"


def instances(rng, n, extent):
    out = {}
    for i in range(n):
        centre = [float(v) for v in rng.uniform(-0.5, extent + 0.5, 2)] + [float(rng.uniform(0.2, 1.0))]
        size = [float(v) for v in rng.uniform(0.1, 1.5, 3)]
        results = {c: float(a) for c, a in zip(CLASSES[:3], rng.gamma(1.0, 3.0, 3))}
        out[str(i)] = {"bbox": {"center": centre, "size": size}, "results": results,
                       "n_observations": int(rng.integers(0, 4))}
    return {"instances": out}


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("gas_probs", [None, np.array([0.3, 0.7])])
def test_blocks_equal_the_dense_column_sum(seed, gas_probs):
    rng = np.random.default_rng(seed)
    grid = GridMap(np.zeros((13, 17), bool), 0.25, (-0.3, 0.2))
    data = instances(rng, 6, 4.0)  # some boxes reach past the map, some have no observations
    lik = LIKELIHOOD if gas_probs is not None else LIKELIHOOD[0]
    dense = semantic_source_probability(voxeland_class_beliefs(data, CLASSES, grid=grid, class_prior=PRIOR), lik,
                                        PRIOR, gas_probs=gas_probs, column_axis=2)
    for block_bytes in (1, 4096, 64 << 20):  # one row per block, a few rows, everything at once
        w = voxeland_column_weights(data, CLASSES, grid=grid, class_prior=PRIOR, source_likelihood=lik,
                                    gas_probs=gas_probs, block_bytes=block_bytes)
        np.testing.assert_allclose(w / w.sum(), dense, rtol=1e-12, atol=0)


def test_no_box_on_the_map_gives_the_prior_everywhere():
    grid = GridMap(np.zeros((3, 4), bool), 0.5)
    data = {"instances": {"0": {"bbox": {"center": [50.0, 50.0, 0.5], "size": [1.0, 1.0, 1.0]},
                                "results": {"oven": 3.0}, "n_observations": 2}}}
    w = voxeland_column_weights(data, CLASSES, grid=grid, class_prior=PRIOR, source_likelihood=LIKELIHOOD[0])
    np.testing.assert_array_equal(w, np.full((3, 4), w[0, 0]))


def test_a_dense_map_too_large_is_refused_naming_the_resolution():
    grid = GridMap(np.zeros((400, 500), bool), 0.01)
    data = {"instances": {"0": {"bbox": {"center": [1.0, 1.0, 1.0], "size": [0.5, 0.5, 2.0]},
                                "results": {"oven": 3.0}, "n_observations": 2}}}
    with pytest.raises(ValueError, match=r"200 layers, the voxel map needs 1\.2 GiB .* coarser resolution "
                                         r"\(>= 0\.0106 m\)"):
        voxeland_class_beliefs(data, CLASSES, grid=grid, class_prior=PRIOR)
    w = voxeland_column_weights(data, CLASSES, grid=grid, class_prior=PRIOR, source_likelihood=LIKELIHOOD[0])
    assert w.shape == (400, 500) and w[100, 100] > w[0, 0]


@pytest.mark.skipif(not HOUSE_B.is_dir(), reason="needs ../shared/data/mapir_house_B")
def test_estimate_on_house_b_at_one_centimetre_stays_under_2_gb(tmp_path):
    """The lab's 1-cm map, furniture boxes up to 1.8 m: 180 layers, a dense voxel map of ~11 GiB, never built."""
    import json

    pytest.importorskip("PIL", reason="the map's PGM image is read with Pillow (the sim extra)")

    from psgsl_pgm.sim import load_ros_map

    fine = load_ros_map(HOUSE_B / "_occupancy.yaml")
    assert fine.resolution == pytest.approx(0.01)
    np.save(tmp_path / "g.npy", np.full(fine.shape, 1 / fine.shape[0] / fine.shape[1]))
    boxes = {"0": ([1.0, 2.0, 0.45], [0.6, 0.6, 0.9], {"oven": 8.0, "microwave": 1.0}),
             "1": ([2.0, 2.5, 0.9], [0.7, 0.7, 1.8], {"refrigerator": 9.0}),
             "2": ([-2.0, 1.0, 0.4], [0.5, 0.7, 0.8], {"toilet": 5.0, "sink": 1.0})}
    (tmp_path / "v.json").write_text(json.dumps({"instances": {
        k: {"bbox": {"center": c, "size": s}, "results": r, "n_observations": 3} for k, (c, s, r) in boxes.items()}}))
    run = ("import resource, sys; from psgsl_pgm.cli._main import main; code = main(sys.argv[1:]); "
           "print('maxrss_kib', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, file=sys.stderr); sys.exit(code)")
    done = subprocess.run([sys.executable, "-c", run, "estimate", "--ontology", str(HOUSE_B / "ontology.yaml"),
                           "--class-probs", str(tmp_path / "v.json"), "--map", str(HOUSE_B / "_occupancy.yaml"),
                           "--olfactory", str(tmp_path / "g.npy"), "--gas", "smoke", "--other-classes",
                           "--out", str(tmp_path / "s.npy")], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    peak_kib = int(done.stderr.split("maxrss_kib")[1].split()[0])
    assert peak_kib < 2 * 1024**2, f"peak RSS {peak_kib / 1024:.0f} MiB"
    post = np.load(tmp_path / "s.npy")
    assert post.shape == fine.shape and np.isclose(post.sum(), 1.0)
