"""Import pgmpy without the warnings its own import emits (imported first by ``psgsl_pgm.networks``).

pgmpy 1.1 warns while importing itself: a ``FutureWarning`` that its own ``pgmpy.estimators`` imports a
deprecated ``StructureScore``, and — in a Jupyter kernel without ipywidgets — tqdm's "IProgress not found"
warning from its ``tqdm.auto`` import. Neither concerns a user of this package, and both would print into
every teaching notebook's first cell. Exactly those two are silenced, for the duration of pgmpy's import
only; every later warning (ours, pgmpy's at run time) is left alone.
"""

from __future__ import annotations

import warnings

__all__: list = []

with warnings.catch_warnings():
    warnings.filterwarnings("ignore", message=r"IProgress not found", module=r"tqdm(\.|$)")
    warnings.filterwarnings("ignore", category=FutureWarning, module=r"pgmpy\.estimators(\.|$)")
    import pgmpy.factors.discrete  # noqa: F401
    import pgmpy.inference  # noqa: F401
    import pgmpy.models  # noqa: F401
    import pgmpy.readwrite  # noqa: F401
