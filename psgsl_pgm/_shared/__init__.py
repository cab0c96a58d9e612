"""The one validation vocabulary every layer uses (``_validate``): distributions, sums, shapes, dtypes and the
messages that name what was expected and what arrived.

May import: numpy. Nothing of the package.
"""

__all__: list = []
