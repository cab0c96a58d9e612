"""Every numba kernel and its helpers: one compiled code path per computation, float32 kept float32.

``_belief`` (the semantic term, fusion and information gain over cells), ``_sight`` (line of sight), ``_view``
(field-of-view gains), ``_filaments`` (the filament gas model's time steps and concentration sums),
``_prefetch`` (chunk prefetching), ``_cache`` (the on-disk kernel cache in the user's cache directory, not
site-packages). Private: the public functions in :mod:`psgsl_pgm.core`,
:mod:`psgsl_pgm.geometry` and :mod:`psgsl_pgm.sim` validate their arguments and call these.

May import: numpy, numba. Nothing of the package.
"""

__all__: list = []
