"""The one validation vocabulary every layer uses (``_validate``): distributions, sums, shapes, dtypes and the
messages that name what was expected and what arrived; and bounded in-process caches keyed by content
(``_memo``), for what a worker computes once per house.

May import: numpy. Nothing of the package.
"""

__all__: list = []
