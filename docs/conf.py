"""Sphinx configuration of the psgsl-pgm documentation.

Build (warnings are errors, every internal reference checked):

    python -m sphinx -W -b html docs docs/_build/html

The teaching notebooks (``notebooks/*.ipynb``, stored without outputs) are executed by myst-nb during the build,
so every page shows its numbers and figures; the short examples (``examples/*.py``) are executed by
sphinx-gallery. Both run with this worktree's ``psgsl_pgm`` first on the path.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent

# The package documented is the one next to these docs, also in the notebook kernels myst-nb starts.
sys.path.insert(0, str(ROOT))
os.environ["PYTHONPATH"] = os.pathsep.join([str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])
# Figures must be captured as images: matplotlib's inline backend sends every figure of a cell to the notebook as
# image/png when the cell ends. Agg (what CI exports as MPLBACKEND for the tests) would draw nothing into the page.
os.environ["MPLBACKEND"] = "module://matplotlib_inline.backend_inline"
os.environ.setdefault("PYTHONHASHSEED", "0")

import psgsl_pgm  # noqa: E402  (after the path is set)

project = "psgsl-pgm"
author = "psgsl-pgm developers"
copyright = "psgsl-pgm developers, GPL-3.0-or-later"  # noqa: A001  (Sphinx's name)
release = psgsl_pgm.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    # MathJax 3 copied into the site's _static/mathjax and loaded from there (mathjax_path), never from a CDN:
    # the site typesets its formulas offline. The module's name has hyphens; Sphinx imports it by that name.
    "sphinx-mathjax-offline",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_nb",
    "sphinx_gallery.gen_gallery",
    # names in code (notebook cells, guides' snippets, gallery examples) link to their API pages, and each API
    # page lists the pages whose code uses it ("examples using X")
    "sphinx_codeautolink",
]

# ---------------------------------------------------------------- sources
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "**.ipynb_checkpoints", "auto_examples/*.ipynb",
                    "auto_examples/*.py", "auto_examples/*.zip", "auto_examples/*.json", "auto_examples/*.md5",
                    "README.md", "teaching/notebooks/README.md"]
templates_path = ["_templates"]
nitpicky = True
# Names from outside this package: there is no network at build time, so no intersphinx inventories; these are
# left unlinked instead of failing the build. Everything of psgsl_pgm itself must resolve.
nitpick_ignore_regex = [
    (r"py:.*", r"(numpy|np|scipy|dask|da|matplotlib|mpl|plt|pgmpy|networkx|nx|pathlib|os|collections|typing|abc|"
               r"concurrent|multiprocessing|distributed|zarr|PIL|tqdm|lifelines|types|rosbags|mcap|foxglove)(\..*)?"),
    (r"py:class", r"(array[_-]like|ndarray|optional|callable|iterable|sequence|mapping|path-like|file-like|"
                  r"int|float|bool|str|bytes|dict|list|tuple|set|None|object|type|slice|complex|"
                  r"Path|Axes|Figure|Generator|Iterable|Iterator|Sequence|Mapping|Callable|Any)"),
]

# ---------------------------------------------------------------- autodoc, autosummary, numpydoc
autosummary_generate = True
autosummary_imported_members = True
autosummary_ignore_module_all = False
autodoc_default_options = {"members": True, "inherited-members": False, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "none"  # the numpydoc sections state the types (with shapes)
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks = set()

# ---------------------------------------------------------------- myst / myst-nb
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
nb_execution_mode = os.environ.get("PSGSL_DOCS_EXECUTE", "force")  # "cache" reuses outputs while editing
nb_execution_timeout = 180  # seconds per cell (each notebook runs in well under a minute)
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_execution_allow_errors = False
nb_merge_streams = True
nb_execution_cache_path = str(DOCS / "_build" / ".jupyter_cache")

# ---------------------------------------------------------------- sphinx-gallery: short examples
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": str(DOCS / "auto_examples"),
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "abort_on_example_error": True,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib",),
    "show_memory": False,
    "show_signature": False,
    # the execution-times page loads DataTables, jQuery and Bootstrap from CDNs: the site must read offline
    "write_computation_times": False,
    # names of the package in the examples' code link to their reference pages, and each reference page lists the
    # examples that use it ("Examples using ...", the minigallery of docs/_templates/autosummary)
    "doc_module": ("psgsl_pgm",),
    "reference_url": {"psgsl_pgm": None},
    "backreferences_dir": str(DOCS / "reference" / "api" / "backreferences"),
}

# ---------------------------------------------------------------- the reference: one page per public package
#: The public packages, in the order the reference lists them (docs/architecture.md: every public name is
#: imported from one of these). Their pages are written from ``__all__`` at every build, so no name is missed.
PUBLIC_PACKAGES = ("psgsl_pgm", "psgsl_pgm.networks", "psgsl_pgm.olfaction", "psgsl_pgm.sim",
                   "psgsl_pgm.experiment", "psgsl_pgm.search", "psgsl_pgm.ros", "psgsl_pgm.teaching", "psgsl_pgm.gym")
API = DOCS / "reference" / "api"


def _api_page(modname: str, seen: dict) -> str:
    """The reST of one package's reference page; ``seen`` maps id(object) to the page that documents it."""
    import importlib
    import inspect

    module = importlib.import_module(modname)
    groups = {"Classes": [], "Functions": [], "Constants": [], "Also here": []}
    for name in module.__all__:
        obj = getattr(module, name)
        if not (inspect.isclass(obj) or callable(obj)):
            groups["Constants"].append(name)
        elif id(obj) in seen:  # re-exported: documented once, where it is first listed
            groups["Also here"].append((name, seen[id(obj)]))
        else:
            seen[id(obj)] = f"{modname}.{name}"
            groups["Classes" if inspect.isclass(obj) else "Functions"].append(name)
    lines = [modname, "=" * len(modname), "", f".. automodule:: {modname}", "   :no-members:", "",
             f".. currentmodule:: {modname}", ""]
    for title in ("Classes", "Functions"):
        if groups[title]:
            lines += [title, "-" * len(title), "", ".. autosummary::", "   :toctree: generated", "",
                      *(f"   {n}" for n in groups[title]), ""]
    if groups["Constants"]:
        lines += ["Constants", "---------", ""]
        for n in groups["Constants"]:
            lines += [f".. autodata:: {n}", ""]
    if groups["Also here"]:
        lines += ["Also importable from here", "-------------------------", ""]
        lines += [f"* ``{modname}.{n}`` is :obj:`{target}`" for n, target in groups["Also here"]]
        lines += [""]
    return "\n".join(lines)


def _write_api_pages() -> None:
    API.mkdir(parents=True, exist_ok=True)
    seen: dict = {}
    for modname in PUBLIC_PACKAGES:
        path = API / f"{modname}.rst"
        text = _api_page(modname, seen)
        if not path.exists() or path.read_text() != text:  # unchanged pages keep their time stamp
            path.write_text(text)


_write_api_pages()


# ---------------------------------------------------------------- HTML
html_theme = "pydata_sphinx_theme"
html_title = f"psgsl-pgm {release}"
html_static_path = ["_static"]
html_css_files = ["psgsl.css"]
html_show_sourcelink = False
html_sourcelink_suffix = ""  # the copied sources keep their own suffix: a notebook downloads as .ipynb
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "header_links_before_dropdown": 7,
    # a notebook's page also offers the notebook itself (docs/_templates/download-notebook.html: empty elsewhere)
    "secondary_sidebar_items": ["download-notebook", "page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_sidebars = {"changelog": [], "getting-started": []}
# The theme reads its light/dark mode from the page; without a default it logs a console error on a first visit.
html_context = {"default_mode": "auto"}


# ---------------------------------------------------------------- module constants' doc comments
def _constant_doc(app, what, name, obj, options, lines):
    """A constant re-exported by a public package keeps the ``#:`` comment of the private module defining it."""
    if what != "data" or not name.startswith("psgsl_pgm."):
        return
    from sphinx.pycode import ModuleAnalyzer

    public, attr = name.rsplit(".", 1)
    package = sys.modules.get(public)
    folder = Path(getattr(package, "__file__", "")).parent
    for source in sorted(folder.glob("_*.py")):
        try:
            docs = ModuleAnalyzer.for_module(f"{public}.{source.stem}").find_attr_docs()
        except Exception:  # noqa: BLE001 - a module the analyzer cannot read has no comment to offer
            continue
        if ("", attr) in docs:
            lines[:] = list(docs[("", attr)])
            return


# ---------------------------------------------------------------- references the Python domain cannot place
# A docstring names objects as its own module sees them: ``:func:`fit_encounter_scale``` inside a private module,
# ``:class:`GridMap``` in psgsl_pgm.sim (documented once, as psgsl_pgm.GridMap), an inherited method. When Sphinx
# finds no target, the name is looked up as Python would from the docstring's module and class: an object the
# reference documents is linked wherever it is documented; a real object of the package that is private (not a
# contract, so not documented) is shown as plain text. A name that is no object at all still fails the build.
_DOCUMENTED: dict = {}


def _lookup(dotted: str):
    """The object named by a dotted path (module part imported, then attributes found statically), or raise."""
    import importlib

    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for attr in parts[cut:]:
            if isinstance(obj, type):  # the raw class attribute: a classmethod, property or function, not a binding
                for klass in obj.__mro__:
                    if attr in vars(klass):
                        obj = vars(klass)[attr]
                        break
                else:
                    raise AttributeError(dotted)
            else:
                obj = getattr(obj, attr)
        return obj
    raise ImportError(dotted)


def _identity(obj):
    """A key for the object itself; None for values whose identity says nothing (numbers, booleans, None)."""
    if obj is None or isinstance(obj, (bool, int, float, complex)):
        return None
    return id(getattr(obj, "__func__", obj))


def _documented(env) -> dict:
    """id(object) -> (full name, entry) of every object the Python domain documents."""
    objects = env.get_domain("py").objects
    if _DOCUMENTED.get("_count") != len(objects):
        _DOCUMENTED.clear()
        for name, entry in objects.items():
            try:
                key = _identity(_lookup(name))
            except Exception:  # noqa: BLE001 - a documented name that does not import (a module's label) is skipped
                continue
            if key is not None:
                _DOCUMENTED.setdefault(key, (name, entry))
        _DOCUMENTED["_count"] = len(objects)
    return _DOCUMENTED


def _contexts(node) -> list:
    """Where the reference's name may live: the docstring's own object, its class and module, the page's context."""
    import re

    places = []
    match = re.search(r"docstring of ([\w.]+)", str(node.source or ""))
    if match:
        owner = match.group(1).split(".")
        places += [".".join(owner[:cut]) for cut in range(len(owner), 0, -1)]
    module, klass = node.get("py:module"), node.get("py:class")
    if module and klass:
        places.append(f"{module}.{klass}")
    if module:
        places.append(module)
    return [*places, *PUBLIC_PACKAGES]


def _missing_reference(app, env, node, contnode):
    import re

    from sphinx.util.nodes import make_refnode

    if node.get("refdomain") != "py":
        return None
    target = node["reftarget"].lstrip("~.")
    documented = _documented(env)
    for place in ["", *_contexts(node)]:
        dotted = f"{place}.{target}" if place else target
        try:
            obj = _lookup(dotted)
        except Exception:  # noqa: BLE001 - not there: try the next place
            continue
        found = documented.get(_identity(obj)) if _identity(obj) is not None else None
        if found is None and dotted in env.get_domain("py").objects:
            found = (dotted, env.get_domain("py").objects[dotted])
        if found is not None:
            name, entry = found
            return make_refnode(app.builder, node["refdoc"], entry.docname, entry.node_id, contnode, name)
        if dotted.startswith("psgsl_pgm."):
            return contnode  # a private object of the package: named, not linked
    # An instance attribute (set in __init__) exists on no class: it is documented in its class's docstring
    # ("Attributes" or "Parameters"), so the reference links to that class.
    for place in ["", *_contexts(node)]:
        dotted = f"{place}.{target}" if place else target
        owner_name, _, attr = dotted.rpartition(".")
        try:
            owner = _lookup(owner_name)
        except Exception:  # noqa: BLE001 - not there: try the next place
            continue
        if isinstance(owner, type) and re.search(rf"^\s*{re.escape(attr)}\s*:", owner.__doc__ or "", re.M):
            found = documented.get(_identity(owner))
            if found is not None:
                name, entry = found
                return make_refnode(app.builder, node["refdoc"], entry.docname, entry.node_id, contnode, name)
    return None


#: The paper's labelled equations: its own number (a count of its numbered equation environments) -> LaTeX label.
#: Each links to its equation on the reference's "Paper <-> code" page, which tabulates all 31.
PAPER_EQUATIONS = {1: "decomposition-objective", 11: "combined-conditionals", 15: "pZcGivenSc",
                   20: "prob-semantics-final"}


def _link_equations(app, what, name, obj, options, lines):
    """``eq. (20)`` in a docstring becomes a link to that equation; a LaTeX label cited as ````label```` shows the
    paper's number and links the same way."""
    import re

    numbers = "|".join(str(n) for n in PAPER_EQUATIONS)
    by_label = {label: n for n, label in PAPER_EQUATIONS.items()}
    cited = re.compile(r"\b([Ee]qs?\.) \((" + numbers + r")\)(?!\w)")
    labelled = re.compile(r"``(" + "|".join(map(re.escape, by_label)) + r")``")
    lines[:] = [labelled.sub(lambda m: f":ref:`({by_label[m.group(1)]}) <eq-{m.group(1)}>`",
                             cited.sub(lambda m: f"{m.group(1)} :ref:`({m.group(2)}) "
                                                 f"<eq-{PAPER_EQUATIONS[int(m.group(2))]}>`", line))
                for line in lines]


def _notebook_links(app, doctree):
    """A Markdown link to a teaching notebook (``[03](notebooks/03_fusion.ipynb)``, written so that it also works
    on GitHub) goes through docs/teaching/notebooks, a link to the repository's notebooks/; Sphinx resolves the
    link to the notebook's real path, outside the source folder. Point it at the page the toctree builds."""
    from sphinx import addnodes

    real = (ROOT / "notebooks").as_posix()
    for node in doctree.findall(addnodes.pending_xref):
        target = node.get("reftarget", "")
        if node.get("refdomain") == "doc" and target.startswith(real + "/"):
            node["reftarget"] = "teaching/notebooks/" + target[len(real) + 1:]


# ---------------------------------------------------------------- code links (sphinx-codeautolink)
codeautolink_concat_default = True  # a page's code blocks run in order: an import in one cell names the next ones
codeautolink_autodoc_inject = True  # every API page ends with the pages whose code uses it
codeautolink_global_preface = "import psgsl_pgm"
# Examples shown but not run (``# doctest: +SKIP``, minutes each) lose the flag in the page (trim_doctest_flags), so
# codeautolink cannot find them in the HTML: those few blocks stay without links instead of failing the build.
suppress_warnings = ["codeautolink.match_block"]


def _gallery_links_by_gallery(app, docname, source):
    """The gallery's pages keep sphinx-gallery's own code links (it ran the code); codeautolink skips them."""
    if docname.startswith("auto_examples/"):
        source[0] = ".. autolink-skip:: file\n\n" + source[0]


def setup(app):
    app.connect("doctree-read", _notebook_links)
    app.connect("autodoc-process-docstring", _constant_doc)
    app.connect("autodoc-process-docstring", _link_equations)
    app.connect("missing-reference", _missing_reference)
    app.connect("source-read", _gallery_links_by_gallery)
