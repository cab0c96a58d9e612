"""Where numba keeps this package's compiled kernels: a user cache directory, never inside the installed package.

numba's default for ``cache=True`` is the ``__pycache__`` folder beside the source file. For a regular install that
is ``site-packages/psgsl_pgm/__pycache__``, a folder pip does not know about: uninstalling (or replacing the
install by an editable one, ``pip install -e``) leaves it behind, and the left-over ``site-packages/psgsl_pgm``
then shadows the real package as an empty namespace package.

:class:`PackageCacheLocator` puts this package's kernels where numba's own user-wide locator would, in
``$XDG_CACHE_HOME/numba`` (``~/.cache/numba``), one folder per installed copy of the package (``kernels_`` and a
hash of the kernels' folder, as numba names it). It is put first in numba's list of CPU cache locators when a
kernel module of this package imports numba, and it answers only for functions defined in this package's files, so other packages'
caches stay where numba puts them. The user's own choice wins: with ``NUMBA_CACHE_DIR`` set, numba's locator
for that directory is used; with ``NUMBA_CACHE_LOCATOR_CLASSES`` set, numba uses that list and ignores this one.
When the user cache directory cannot be written, numba's next locator (the in-tree ``__pycache__``) is used, as
before.

Trade-off: the list of locators is a private attribute of numba (``CacheImpl._locator_classes`` in
``numba.core.caching``; a test checks that it still takes effect). Setting ``NUMBA_CACHE_DIR`` from here instead
would use only public API, but would move every other package's cache too, and only if psgsl_pgm imported numba
first. The cache entries outlive an uninstall (in the user cache folder, where caches are expected); they are
keyed, as always, by the content hash of the source file, so a stale entry is never loaded.
"""

from __future__ import annotations

import os

from numba.core import caching, config

__all__ = ["PackageCacheLocator", "register"]

_PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # psgsl_pgm/, not kernels/


class PackageCacheLocator(caching.UserWideCacheLocator):
    """numba's user-wide cache locator, for the functions of this package only."""

    @classmethod
    def from_function(cls, py_func, py_file):
        if config.CACHE_DIR:  # NUMBA_CACHE_DIR: numba's UserProvidedCacheLocator takes the function
            return None
        if not os.path.abspath(py_file).startswith(_PACKAGE_DIR + os.sep):  # another package's function
            return None
        return super().from_function(py_func, py_file)


def register() -> None:
    """Put :class:`PackageCacheLocator` first among numba's CPU cache locators (once)."""
    classes = caching.CacheImpl._locator_classes
    if PackageCacheLocator not in classes:
        classes.insert(0, PackageCacheLocator)


register()
