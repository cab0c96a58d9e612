"""Every notebook under notebooks/ runs top to bottom without error or warning, and is committed without outputs.

Executing a notebook also checks what a student sees: no cell may print to stderr or show a warning (a
teaching notebook's output must be clean), and every figure left open at the end is held to the package's
readability rules (:func:`psgsl_pgm.teaching.figure_problems`: labelled axes, a labelled colour bar for every
image whose colour carries a value).

The kernel is the interpreter running pytest: a kernelspec pointing at ``sys.executable`` is written to a
temporary directory and used through its own KernelSpecManager, so a user-level "python3" kernelspec of
another Python cannot be picked up. matplotlib gets the non-interactive Agg backend through MPLBACKEND in
the kernel's environment (the notebooks themselves just plot).
"""

from __future__ import annotations

import json
import os
import re
import sys
from pathlib import Path

import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOK_DIR = ROOT / "notebooks"
NOTEBOOKS = sorted(NOTEBOOK_DIR.glob("*.ipynb"))
CELL_TIMEOUT = 120  # seconds per cell
KERNEL_NAME = "psgsl-pgm-test"
#: The widest figure a page shows legibly: the article column is about 800 px, so a figure of 10-pt labels drawn
#: at 100 dpi keeps its text at 9 px or more up to 12.5 in.
MAX_WIDTH_IN = 12.5
#: Appended to each notebook before it runs: the readability problems of every figure still open (the package's
#: rules, and a width the page's column shows without shrinking the text past reading).
FIGURE_CHECK = f"MAX_WIDTH_IN = {MAX_WIDTH_IN}\n" + """\
import json as _json
import matplotlib.pyplot as _plt
from psgsl_pgm.teaching import figure_problems as _figure_problems

def _width_problems(fig, widest=MAX_WIDTH_IN):
    width = float(fig.get_size_inches()[0])
    if width <= widest:
        return []
    return [f"{width:.1f} in wide: the article column would shrink its text below 9 px (at most {widest} in)"]


print(_json.dumps({str(_n): _figure_problems(_plt.figure(_n)) + _width_problems(_plt.figure(_n))
                   for _n in _plt.get_fignums()}))
"""
#: A warning as Python prints it ("…: SomethingWarning: message"), wherever it shows up in an output.
WARNING = re.compile(r"\b\w*Warning\b")
#: A cell's last expression left unassigned (``fig.colorbar(...)``): its default repr, "<… at 0x…>".
STRAY_REPR = re.compile(r"<[\w.]+(?: object)? at 0x[0-9a-f]+>")


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


def _output_text(output) -> str:
    if output.get("output_type") == "stream":
        return output.get("text", "")
    return "".join(str(v) for k, v in output.get("data", {}).items() if k.startswith("text/"))


def output_problems(nb) -> list:
    """Cells of an executed notebook that wrote to stderr or show a warning (in any output)."""
    problems = []
    for i, cell in enumerate(c for c in nb.cells if c.cell_type == "code"):
        for out in cell.get("outputs", []):
            text = _output_text(out)
            if out.get("output_type") == "stream" and out.get("name") == "stderr":
                problems.append(f"code cell {i} writes to stderr: {text.strip()[:300]!r}")
            elif WARNING.search(text):
                problems.append(f"code cell {i} shows a warning: {text.strip()[:300]!r}")
            elif out.get("output_type") == "execute_result" and STRAY_REPR.search(text):
                problems.append(f"code cell {i} shows an object's repr: {text.strip()[:300]!r}")
    return problems


def test_output_problems_finds_stderr_and_warnings():
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("1"), nbformat.v4.new_code_cell("2")])
    nb.cells[0].outputs = [nbformat.v4.new_output("stream", name="stdout", text="p = 0.5\n")]
    assert output_problems(nb) == []
    nb.cells[1].outputs = [nbformat.v4.new_output("stream", name="stderr", text="x.py:3: UserWarning: hm\n")]
    assert output_problems(nb) == ["code cell 1 writes to stderr: 'x.py:3: UserWarning: hm'"]
    nb.cells[1].outputs = [nbformat.v4.new_output("execute_result", data={"text/plain": "FutureWarning: y"})]
    assert output_problems(nb) == ["code cell 1 shows a warning: 'FutureWarning: y'"]
    nb.cells[1].outputs = [nbformat.v4.new_output(
        "execute_result", data={"text/plain": "<matplotlib.colorbar.Colorbar at 0x7f3a2c1d0e50>"})]
    assert output_problems(nb) == ["code cell 1 shows an object's repr: "
                                   "'<matplotlib.colorbar.Colorbar at 0x7f3a2c1d0e50>'"]
    nb.cells[1].outputs = [nbformat.v4.new_output("execute_result", data={"text/plain": "(4, True)"})]
    assert output_problems(nb) == []


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs(path, kernel_spec_dir):
    """No error (nbclient raises CellExecutionError with the traceback), no warning, readable figures."""
    nb = nbformat.read(path, as_version=4)
    nb.cells.append(nbformat.v4.new_code_cell(FIGURE_CHECK))
    out = _execute(nb, kernel_spec_dir, path.parent)
    check = out.cells.pop()
    assert output_problems(out) == [], f"{path.name}: a teaching notebook's output must be clean"
    figures = json.loads("".join(o.get("text", "") for o in check.outputs if o.get("name") == "stdout"))
    unreadable = {n: p for n, p in figures.items() if p}
    assert not unreadable, f"{path.name}: figures a reader cannot read: {unreadable}"
