"""The one validation vocabulary every layer uses (``_validate``): distributions, sums, shapes, dtypes and the
messages that name what was expected and what arrived; and bounded in-process caches keyed by content
(``_memo``), for what a worker computes once per house; and the guard that keeps the process's floating-point
environment IEEE 754 around foreign compiled code built with fast math (``_fpenv``).

May import: numpy. Nothing of the package.
"""

__all__: list = []
