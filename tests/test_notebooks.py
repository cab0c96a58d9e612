"""Every notebook under notebooks/ runs top to bottom without error, and is committed without outputs.

The kernel is the interpreter running pytest: a kernelspec pointing at ``sys.executable`` is written to a
temporary directory and used through its own KernelSpecManager, so a user-level "python3" kernelspec of
another Python cannot be picked up. matplotlib gets the non-interactive Agg backend through MPLBACKEND in
the kernel's environment (the notebooks themselves just plot).
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOK_DIR = ROOT / "notebooks"
NOTEBOOKS = sorted(NOTEBOOK_DIR.glob("*.ipynb"))
CELL_TIMEOUT = 120  # seconds per cell
KERNEL_NAME = "psgsl-pgm-test"


@pytest.fixture(scope="session")
def kernel_spec_dir(tmp_path_factory):
    """A kernelspec directory whose only kernel runs ``sys.executable -m ipykernel_launcher``."""
    root = tmp_path_factory.mktemp("kernels")
    spec = root / KERNEL_NAME
    spec.mkdir()
    (spec / "kernel.json").write_text(json.dumps({
        "argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"],
        "display_name": f"psgsl-pgm tests ({sys.executable})",
        "language": "python",
    }))
    return root


def _execute(nb, kernel_spec_dir, cwd: Path):
    """Run ``nb`` in a fresh kernel that nbclient owns (it starts and shuts it down)."""
    from jupyter_client.kernelspec import KernelSpecManager
    from jupyter_client.manager import AsyncKernelManager
    from nbclient import NotebookClient

    class _ThisInterpreter(AsyncKernelManager):
        """Finds kernels only in ``kernel_spec_dir``."""

        def __init__(self, **kwargs):
            kwargs.setdefault("kernel_spec_manager", KernelSpecManager(kernel_dirs=[str(kernel_spec_dir)]))
            super().__init__(**kwargs)

    client = NotebookClient(nb, kernel_manager_class=_ThisInterpreter, timeout=CELL_TIMEOUT,
                            kernel_name=KERNEL_NAME, resources={"metadata": {"path": str(cwd)}})
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONHASHSEED": "0"}
    return client.execute(env=env)


def test_there_are_notebooks():
    assert len(NOTEBOOKS) >= 6, f"expected the teaching notebooks under {NOTEBOOK_DIR}"


def test_kernel_is_this_interpreter(kernel_spec_dir, tmp_path):
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("import sys, os\nprint(sys.executable)\n"
                                                                   "print(os.environ['MPLBACKEND'])")])
    out = _execute(nb, kernel_spec_dir, tmp_path)
    text = "".join(o.get("text", "") for o in out.cells[0].outputs).split()
    assert Path(text[0]).resolve() == Path(sys.executable).resolve()
    assert text[1] == "Agg"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_is_committed_without_outputs(path):
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert code, f"{path.name} has no code cells"
    for i, cell in enumerate(code):
        assert cell.outputs == [] and cell.execution_count is None, f"{path.name}: code cell {i} has outputs"


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs(path, kernel_spec_dir):
    """nbclient raises CellExecutionError (with the traceback) on the first failing cell."""
    nb = nbformat.read(path, as_version=4)
    _execute(nb, kernel_spec_dir, path.parent)
