"""numba's on-disk cache of the kernels lives in the user cache folder, never inside the package, and a second
process loads it instead of compiling (psgsl_pgm.kernels._cache)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "psgsl_pgm"

# Calls one kernel and prints, per cached dispatcher of the three kernel modules, its cache folder (chosen when the
# function is decorated) and its cache hits and misses so far.
_CALL_KERNELS = """
import json
import numpy as np
from psgsl_pgm import semantic_source_probability
from psgsl_pgm.kernels import _belief as _kernel, _sight as _sight_kernel, _view as _view_kernel

semantic_source_probability(np.full((3, 2), 0.5), [0.5, 0.5], [0.5, 0.5])
out = {}
for m in (_kernel, _sight_kernel, _view_kernel):
    for n in dir(m):
        d = getattr(m, n)
        if getattr(d, "_cache", None) is not None and hasattr(d, "stats"):
            out[f"{m.__name__}.{n}"] = [str(d._cache._cache_path), sum(d.stats.cache_hits.values()),
                                        sum(d.stats.cache_misses.values())]
print(json.dumps(out))
"""

WEIGHTS = "psgsl_pgm.kernels._belief._belief_weights"


def _run(tmp_path, **env_extra):
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_CACHE")}
    env.update(PYTHONPATH=str(ROOT), XDG_CACHE_HOME=str(tmp_path / "xdg"), **env_extra)
    out = subprocess.run([sys.executable, "-c", _CALL_KERNELS], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def _nb_files(folder: Path):
    return sorted(p.name for p in folder.rglob("*") if p.suffix in (".nbi", ".nbc"))


def test_kernels_are_cached_in_the_user_cache_folder_and_reused_by_the_next_process(tmp_path):
    in_tree_before = _nb_files(PACKAGE)
    first = _run(tmp_path)
    assert {m.rsplit(".", 1)[0] for m in first} == {f"psgsl_pgm.kernels.{m}" for m in ("_belief", "_sight",
                                                                                     "_view")}
    folder = tmp_path / "xdg" / "numba"
    for name, (path, _, _) in first.items():
        assert Path(path).parent == folder and Path(path).name.startswith("kernels_"), (name, path)
    assert first[WEIGHTS][1:] == [0, 1]  # compiled once, in this fresh cache
    cached = _nb_files(folder)
    assert any(n.startswith("_belief._belief_weights-") and n.endswith(".nbi") for n in cached)
    assert _nb_files(PACKAGE) == in_tree_before  # nothing new beside the sources
    second = _run(tmp_path)
    assert second[WEIGHTS] == [first[WEIGHTS][0], 1, 0]  # loaded from disk by the next process, not compiled


def test_numba_cache_dir_set_by_the_user_wins(tmp_path):
    got = _run(tmp_path, NUMBA_CACHE_DIR=str(tmp_path / "mine"))
    assert all(Path(path).parent == tmp_path / "mine" for path, _, _ in got.values())
    assert not (tmp_path / "xdg" / "numba").exists()


def test_other_packages_functions_keep_numbas_own_locator(tmp_path):
    # a cached function outside the package: numba's in-tree locator, as without psgsl_pgm
    (tmp_path / "other.py").write_text("import numba\n@numba.njit(cache=True)\ndef f(x):\n    return x + 1\n")
    code = ("import psgsl_pgm.kernels._cache, other\nother.f(1)\nprint(other.f.stats.cache_path)")
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_CACHE")}
    env.update(PYTHONPATH=f"{ROOT}{os.pathsep}{tmp_path}", XDG_CACHE_HOME=str(tmp_path / "xdg"))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert Path(out.stdout.strip()) == tmp_path / "__pycache__"
