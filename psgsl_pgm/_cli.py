"""Command line: ``psgsl`` (or ``python -m psgsl_pgm``)."""

from __future__ import annotations

import argparse
import sys

__all__ = ["main"]


def _kitchen(args) -> int:
    from ._kitchen import kitchen_example

    res = kitchen_example()
    print("The paper's kitchen example: smoke; p(o | s) = oven 0.4, microwave 0.25, refrigerator 0.3, countertop 0.05")
    print(f"{'cell':>14} {'p(s|z)':>8} {'p(s|g)':>8} {'p(s|g,z)':>9}")
    for name, s, g, f in zip(res["cells"], res["semantic"], res["olfactory"], res["fused"]):
        print(f"{name:>14} {s:8.4f} {g:8.4f} {f:9.4f}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="psgsl", description="Probabilistic semantic gas source localization.")
    sub = parser.add_subparsers(dest="command")
    sub.add_parser("kitchen", help="the paper's kitchen example on six cells").set_defaults(func=_kitchen)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        args = parser.parse_args(["kitchen"])
    return args.func(args)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
