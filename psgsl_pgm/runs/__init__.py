"""Resumable grids of seeded runs, shared by :mod:`psgsl_pgm.experiment` and :mod:`psgsl_pgm.search`.

``_runner`` runs a grid of jobs (in-process, worker processes or a dask scheduler), stores each finished run
atomically, resumes, and holds one process per output folder (a lock the OS releases on kill -9); ``_key``
keys a folder by the content of every input (world files and the files they name, configs, command, version)
and names what changed when a run would mix two configurations.

May import: :mod:`psgsl_pgm.sim` (world files), :mod:`psgsl_pgm.io`, :mod:`psgsl_pgm._shared`.
"""

__all__: list = []
