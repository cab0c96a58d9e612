"""README's two commands, one after the other in one venv, in either order: the package stays importable and
``psgsl`` runs (no compiled cache inside site-packages that could shadow the editable install)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import venv
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

# What command 1's ``psgsl`` does to the install that matters here: it compiles kernels (numba, cache=True).
_COMPILE = """
import numpy as np
from psgsl_pgm import field_of_view, semantic_source_probability
semantic_source_probability(np.full((3, 2), 0.5), [0.5, 0.5], [0.5, 0.5])
field_of_view(np.zeros((6, 6), bool), (1.0, 1.0, 0.5), max_range=3.0, half_angle=1.0)
"""

_CHECK = """
import psgsl_pgm
from psgsl_pgm import Ontology, kitchen_ontology
print(psgsl_pgm.__file__)
"""


def _source_copy(dest: Path) -> Path:
    """The repository's tracked files (a fresh clone's content), so that installing writes nothing into ROOT."""
    listed = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True).stdout
    for name in filter(None, listed.decode().split("\0")):
        if (ROOT / name).is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, dest / name)
    return dest


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("git") is None or not (ROOT / ".git").exists(), reason="needs the git checkout")
def test_readme_commands_in_either_order_in_one_venv(tmp_path):
    src = _source_copy(tmp_path / "src")
    env_dir = tmp_path / "venv"
    venv.create(env_dir, with_pip=True)
    bin_dir = env_dir / "bin"
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV") and not k.startswith("NUMBA_")}
    env.update(PATH=f"{bin_dir}{os.pathsep}{env['PATH']}", XDG_CACHE_HOME=str(tmp_path / "cache"),
               PIP_DISABLE_PIP_VERSION_CHECK="1", MPLBACKEND="Agg")
    site = Path(subprocess.run([bin_dir / "python", "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                               capture_output=True, text=True, check=True, env=env).stdout.strip())
    work = tmp_path / "work"  # the user's shell: not the source folder, so only the install can be imported
    work.mkdir()

    def run(*cmd):
        out = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, env=env, cwd=work)
        assert out.returncode == 0, f"{cmd}: {out.stdout[-2000:]}{out.stderr[-2000:]}"
        return out.stdout

    def importable(where: Path):
        assert Path(run(bin_dir / "python", "-c", _CHECK).strip()) == where / "psgsl_pgm" / "__init__.py"
        assert "usage: psgsl" in run(bin_dir / "psgsl", "--help")

    # command 1: a regular install, then its kernels compile (their cache goes to the user cache folder)
    run(bin_dir / "pip", "install", "-q", f"{src}[all]")
    run(bin_dir / "python", "-c", _COMPILE)
    importable(site)
    # command 2's install over it: the editable install is the one imported, nothing left behind shadows it
    run(bin_dir / "pip", "install", "-q", "-e", f"{src}[test]")
    importable(src)
    assert not (site / "psgsl_pgm").exists()
    assert list((tmp_path / "cache" / "numba").rglob("*.nbi"))  # command 1's kernels went to the user cache
    run(bin_dir / "python", "-c", _COMPILE)  # the editable copy's kernels: cached in the user folder too
    assert not list((src / "psgsl_pgm").rglob("*.nb[ic]"))
    # and command 1 again, after command 2 (the other order)
    run(bin_dir / "pip", "install", "-q", f"{src}[all]")
    importable(site)
    run(bin_dir / "python", "-c", _COMPILE)
    importable(site)
    assert not list((site / "psgsl_pgm").rglob("*.nb[ic]"))  # no compiled cache inside site-packages
