"""Every public function's reference page describes every parameter of its signature.

The reference is written from the numpydoc docstrings, so a parameter the ``Parameters`` section leaves out is a
parameter a reader of the page cannot learn about. The functions that still leave some out are listed in
``docstring_gaps.txt`` beside this file, one ``name: param, param`` per line: a function not listed, and a parameter
not listed, must be described. Fill a gap, then remove it from the list.

Every public function's page also shows a runnable ``Examples`` section (the doctests run in
``tests/test_doctests.py``). A function that cannot have one yet is listed in ``example_gaps.txt``, one name per line
with the reason as a ``# comment``; a listed function that has gained an example must come off the list.
"""

from __future__ import annotations

import importlib
import inspect
import re
import sys
from pathlib import Path

PUBLIC_PACKAGES = ("psgsl_pgm", "psgsl_pgm.networks", "psgsl_pgm.olfaction", "psgsl_pgm.sim",
                   "psgsl_pgm.experiment", "psgsl_pgm.search", "psgsl_pgm.ros", "psgsl_pgm.teaching",
                   "psgsl_pgm.gym")
GAPS_FILE = Path(__file__).with_name("docstring_gaps.txt")
EXAMPLE_GAPS_FILE = Path(__file__).with_name("example_gaps.txt")
EXAMPLES = re.compile(r"^\s*Examples\n\s*-{4,}", re.M)
SECTION = re.compile(r"^(\s*)Parameters\n\1-{4,}\n(.*?)(?=^\1\S[^\n]*\n\1-{4,}\n|\Z)", re.M | re.S)


def documented_parameters(doc: str) -> set:
    """The names a numpydoc ``Parameters`` section describes (``a, b : int`` names two; ``*args`` is ``args``)."""
    match = SECTION.search(doc or "")
    if match is None:
        return set()
    indent = match.group(1)
    names = set()
    for line in match.group(2).splitlines():
        if line.startswith(indent) and line[len(indent):len(indent) + 1].strip():  # a line at the section's indent
            head = line[len(indent):].split(" :")[0].split(":")[0]
            names.update(n.strip().lstrip("*") for n in head.split(",") if n.strip())
    return names


def public_functions() -> dict:
    """'package.name' -> function, each function once (where its package first lists it)."""
    out, seen = {}, set()
    for package in PUBLIC_PACKAGES:
        try:
            module = importlib.import_module(package)
        except ImportError as err:  # an extra that is not installed (e.g. ros): its functions are not checked
            if package in ("psgsl_pgm", "psgsl_pgm.sim", "psgsl_pgm.search", "psgsl_pgm.experiment"):
                raise
            print(f"skipped {package}: {err}")
            continue
        for name in module.__all__:
            obj = getattr(module, name)
            if inspect.isfunction(obj) and id(obj) not in seen:
                seen.add(id(obj))
                out[f"{package}.{name}"] = obj
    return out


def missing_parameters(func) -> set:
    params = {p.name for p in inspect.signature(func).parameters.values() if p.name not in ("self", "cls")}
    return params - documented_parameters(func.__doc__)


def known_gaps() -> dict:
    gaps = {}
    for line in GAPS_FILE.read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            name, _, params = line.partition(":")
            gaps[name.strip()] = {p.strip() for p in params.split(",") if p.strip()}
    return gaps


def test_the_section_parser_reads_numpydoc():
    doc = """Summary.

    Parameters
    ----------
    a, b : int
        Two.
    c : float, keyword-only
        Three: not a name.
    *args
        More.

    Returns
    -------
    x : int
    """
    assert documented_parameters(doc) == {"a", "b", "c", "args"}
    assert documented_parameters("No sections.") == set()


def test_every_public_function_documents_its_parameters():
    gaps = known_gaps()
    new = {name: sorted(missing_parameters(f) - gaps.get(name, set())) for name, f in public_functions().items()}
    new = {name: params for name, params in new.items() if params}
    assert new == {}, f"parameters the reference does not describe (add them to the docstring): {new}"


def test_the_gap_list_holds_no_filled_gap():
    """A parameter described since it was listed comes off the list, so the list only shrinks to what is left."""
    functions = public_functions()
    stale = {}
    for name, params in known_gaps().items():
        if name not in functions:  # a package of an extra that is not installed, or a name that went away
            if name.rsplit(".", 1)[0] in sys.modules:
                stale[name] = "not a public function"
            continue
        filled = sorted(params - missing_parameters(functions[name]))
        if filled:
            stale[name] = filled
    assert stale == {}, f"docstring_gaps.txt lists parameters that are described now (remove them): {stale}"


def has_examples(func) -> bool:
    """Whether the docstring has a numpydoc ``Examples`` section."""
    return EXAMPLES.search(func.__doc__ or "") is not None


def known_example_gaps() -> dict:
    """'package.name' -> reason, from ``example_gaps.txt`` (``name  # reason`` per line)."""
    gaps = {}
    for line in EXAMPLE_GAPS_FILE.read_text().splitlines():
        name, _, reason = line.partition("#")
        if name.strip():
            gaps[name.strip()] = reason.strip()
    return gaps


def test_the_examples_section_is_recognised():
    def with_example():
        """Summary.

        Examples
        --------
        >>> 1 + 1
        2
        """

    def without():
        """Summary.

        Notes
        -----
        The word Examples in prose is not a section.
        """

    assert has_examples(with_example) and not has_examples(without)


def test_every_public_function_has_an_example():
    gaps = known_example_gaps()
    missing = sorted(name for name, f in public_functions().items() if not has_examples(f) and name not in gaps)
    assert missing == [], f"public functions without an Examples section (add a runnable example): {missing}"


def test_the_example_gap_list_holds_no_filled_gap():
    """A function that has an example since it was listed comes off the list, so the list only shrinks."""
    functions = public_functions()
    stale = {}
    for name in known_example_gaps():
        if name not in functions:  # a package of an extra that is not installed, or a name that went away
            if name.rsplit(".", 1)[0] in sys.modules:
                stale[name] = "not a public function"
            continue
        if has_examples(functions[name]):
            stale[name] = "has an Examples section"
    assert stale == {}, f"example_gaps.txt lists functions that need no entry (remove them): {stale}"
