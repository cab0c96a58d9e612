"""A core-only install (numpy, scipy, PyYAML, numba) runs README's library example; psgsl_pgm.networks names its
extra."""

from __future__ import annotations

import os
import subprocess
import sys
import venv
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

# Imports psgsl_pgm.networks with pgmpy unimportable and prints the ImportError's message.
_HIDE_PGMPY = """
import sys
sys.modules["pgmpy"] = None  # pgmpy cannot be imported, as on a core-only install
import psgsl_pgm, psgsl_pgm.sim  # the core and the simulator import without pgmpy
try:
    import psgsl_pgm.networks
except ImportError as err:
    print(err)
"""


def readme_library_example() -> str:
    text = (ROOT / "README.md").read_text()
    start = text.index("```python", text.index("## The library on your own arrays")) + len("```python")
    return text[start : text.index("```", start)]


def test_networks_without_pgmpy_names_the_extra():
    out = subprocess.run([sys.executable, "-c", _HIDE_PGMPY], capture_output=True, text=True, check=True, cwd=ROOT)
    assert out.stdout.strip() == (
        'psgsl_pgm.networks needs pgmpy (the "networks" extra): pip install "psgsl-pgm[networks]"'
    )


@pytest.mark.slow
def test_core_only_install_runs_the_readme_library_example(tmp_path):
    """A fresh venv without system site packages, ``pip install .``: only the core's dependencies arrive."""
    env_dir = tmp_path / "venv"
    venv.create(env_dir, with_pip=True, system_site_packages=False)
    py = env_dir / "bin" / "python"
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    subprocess.run([py, "-m", "pip", "install", "-q", "--disable-pip-version-check", str(ROOT)], check=True,
                   env=env, cwd=tmp_path)
    listed = subprocess.run([py, "-m", "pip", "list", "--format=freeze"], capture_output=True, text=True,
                            check=True, env=env).stdout
    names = {line.split("==")[0].lower() for line in listed.split()}
    # numpy, scipy, PyYAML, and numba (with its llvmlite) for the core's compiled kernels; nothing else
    assert names - {"pip", "setuptools", "wheel"} == {"numpy", "scipy", "pyyaml", "numba", "llvmlite", "psgsl-pgm"}, names
    (tmp_path / "example.py").write_text(readme_library_example())
    subprocess.run([py, "example.py"], check=True, env=env, cwd=tmp_path)
