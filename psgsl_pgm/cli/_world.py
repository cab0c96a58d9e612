"""``psgsl world check W.yaml [--png out.png]``: validate a world file and summarise (and draw) the house."""

from __future__ import annotations

import os
from pathlib import Path

from ._grid import add_found_arguments

__all__ = ["add_parser", "run", "format_summary", "plot_world"]


def add_parser(subparsers) -> None:
    """Register ``world`` (with its one action, ``check``) on the ``psgsl`` subparsers."""
    world = subparsers.add_parser("world", help="world files: your own house (map, rooms, objects, ontology, wind)")
    actions = world.add_subparsers(dest="world_command", required=True)
    check = actions.add_parser("check", help="validate every file and key of a world file; print a summary")
    check.add_argument("world", help="world file (YAML; see docs/guide/own-house.md)")
    check.add_argument("--png", default=None, help="also draw map, rooms, objects, windows, wind and sources here")
    check.add_argument("--seed", type=int, default=0, help="seed of the house (only the built-in house varies)")
    add_found_arguments(check)
    check.set_defaults(func=run)


def run(args) -> int:
    """Run ``psgsl world check``; bad files or keys raise ValueError (one line, exit 2, nothing written)."""
    from ._usage import LIBRARY_ERRORS, reporting_usage_errors

    return reporting_usage_errors(_check, args, errors=(*LIBRARY_ERRORS, FileNotFoundError))


def _check(args) -> int:
    from ..search import SearchConfig, check_findable
    from ..sim import load_world

    png = None
    if args.png is not None:
        png = Path(args.png)
        if png.suffix.lower() != ".png":
            raise ValueError(f"--png: expected a .png file name, got {args.png!r}")
        if not png.parent.is_dir():
            raise ValueError(f"--png: directory {str(png.parent)!r} does not exist")
    spec = load_world(args.world)
    # a source the robot can never find is refused before anything is printed (one line, exit 2)
    found = check_findable(spec, args.seed, found_radius=args.found_radius, clearance=args.clearance)
    summary = spec.summary(seed=args.seed)
    summary["findability"] = {"found_radius": SearchConfig().found_radius if args.found_radius is None
                              else args.found_radius, "clearance": spec.clearance if args.clearance is None
                              else args.clearance}
    for name, f in found.items():
        summary["sources"][name] |= f
    print(format_summary(summary))
    if png is not None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig = plot_world(spec, seed=args.seed)
        tmp = png.with_name(f".{png.name}.{os.getpid()}.tmp.png")
        try:
            fig.savefig(tmp, dpi=120)
            os.replace(tmp, png)  # atomic: a figure is written whole or not at all
        except OSError as exc:
            raise ValueError(f"--png: cannot write {str(png)!r} ({exc.strerror or exc})") from None
        finally:
            plt.close(fig)
            if tmp.exists():
                tmp.unlink()
        print(f"figure -> {png}")
    return 0


def format_summary(s: dict) -> str:
    """The summary of :meth:`psgsl_pgm.sim.WorldSpec.summary` as text."""
    g = s["grid"]
    x0, x1, y0, y1 = g["extent"]
    lines = [f"world {s['world']}: OK",
             f"grid: {g['rows']} x {g['cols']} cells of {g['resolution']:g} m, x {x0:.2f}..{x1:.2f} m, "
             f"y {y0:.2f}..{y1:.2f} m, {g['free_cells']} free cells",
             "rooms (m²): " + ", ".join(f"{k} {v:.2f}" for k, v in s["rooms"].items())]
    objs = ", ".join(f"{k} {v}" for k, v in s["objects"].items()) or "none"
    lines.append(f"objects per class: {objs}")
    if s["unlisted_classes"]:
        lines.append(f"  classes the ontology does not list (an 'other' for the semantic term): "
                     f"{', '.join(s['unlisted_classes'])}")
    wind = s["wind"]
    if wind["kind"] == "potential":
        lines.append(f"wind: potential flow, mean speed {wind['speed']:g} m/s, perturbation {wind['perturbation']:g}")
    else:
        lines.append(f"wind: GADEN CFD, {wind['snapshots']} snapshot(s) of {wind['period']:g} s at z = "
                     f"{wind['height']:g} m")
    for w in s["windows"]:
        lines.append(f"  {w['role']}: ({w['from'][0]:g}, {w['from'][1]:g}) -> ({w['to'][0]:g}, {w['to'][1]:g}), "
                     f"{w['cells']} cells")
    lines.append(f"start: ({s['start'][0]:.2f}, {s['start'][1]:.2f})")
    if s["sources"]:
        f = s["findability"]
        lines.append(f"found within {f['found_radius']:g} m (of the emitting object's footprint); drivable: "
                     f"{f['clearance']:g} m from walls, furniture and windows")
    for name, src in s["sources"].items():
        x, y = src["position"]
        what = f"object {src['object']} ({src['target_cells']} cells)" if src["object"] else "a point"
        lines.append(f"source {name}: ({x:.2f}, {y:.2f}) in {src['room'] or 'no room'}, {what}; "
                     f"{src['geodesic']:.2f} m from the start, nearest drivable cell {src['gap']:.2f} m from it")
    lines.append(f"source region: {s['source_region']}, {s['source_region_area']:.2f} m²")
    o = s["ontology"]
    lines.append(f"ontology: gases {', '.join(o['gases'])}; classes {', '.join(o['classes'])}")
    if o["rooms"]:
        lines.append(f"  p(o | room) for {', '.join(o['rooms'])}")
        if o["rooms_at_class_prior"]:
            lines.append(f"warning: p(o | room) omits room(s) {', '.join(o['rooms_at_class_prior'])} of the room map: "
                         "they start at the class prior (no room evidence)")
    else:
        lines.append("  no p(o | room) (give room_classes): every room starts at the class prior")
    if s["gas"]:
        lines.append(f"target gas: {s['gas']}")
    if s["semantic_map"] is not None:
        lines.append(f"semantic map: class beliefs of shape {tuple(s['semantic_map'])} (replaces the camera)")
    elif not s["objects"]:
        lines.append("warning: the world lists no objects: the camera variants (semantics, semantics+rooms) will see "
                     "nothing and keep their priors (give an 'objects' file, or a 'semantic_map')")
    from ..sim import MAX_FREE_CELLS

    if g["free_cells"] > MAX_FREE_CELLS:
        lines.append(f"warning: {g['free_cells']:,} free cells: search, experiment, benchmark and replay refuse maps "
                     f"of more than {MAX_FREE_CELLS:,} (their memory); set a coarser 'resolution' for them")
    return "\n".join(lines)


def plot_world(spec, *, seed: int = 0):
    """Figure of a world: rooms, walls, objects, windows, wind arrows, start and sources (axes in metres)."""
    import matplotlib.pyplot as plt
    from matplotlib import transforms

    from ..sim import plot_house, potential_flow
    from ..sim._plot import LABEL_BOX, declutter

    house = spec.house(seed)
    if spec.wind["kind"] == "gaden":
        wind = spec.wind["sequence"].mean()
    else:
        wind = potential_flow(house.grid, house.inlet, house.outlet, mean_speed=spec.wind["speed"])
    h, w = house.shape
    fig, ax = plt.subplots(figsize=(7.5, 7.5 * h / w + 0.8), layout="constrained")
    plot_house(house, ax=ax, wind=wind, wind_stride=max(2, min(h, w) // 25))
    for win in spec.windows_of(house):
        (a, b), (c, d) = win["from"], win["to"]
        ax.plot([a, c], [b, d], color="tab:blue" if win["role"] == "inlet" else "tab:red", lw=3,
                label=win["role"])
    start = spec.start_for(house)
    ax.plot(*start, marker="o", color="white", mec="k", ms=8, ls="none", label="start")
    at: dict = {}  # sources at one position share one label ("B1, oven")
    for name in spec.sources:
        x, y = spec.resolve_source(name, house)
        at.setdefault((round(float(x), 6), round(float(y), 6)), []).append(str(name))
    labels = []
    for (x, y), names in at.items():
        ax.plot(x, y, marker="*", color="red", mec="k", ms=14, ls="none", zorder=7)
        shift = transforms.offset_copy(ax.transData, fig=fig, x=6, y=6, units="points")
        labels.append(ax.text(x, y, ", ".join(names), transform=shift, fontsize=8, color="darkred",
                              bbox=LABEL_BOX, zorder=8, clip_on=True))
    handles, names = ax.get_legend_handles_labels()
    uniq = dict(zip(names, handles))
    if uniq:  # below the map, where it covers nothing
        fig.legend(uniq.values(), uniq.keys(), loc="outside lower center", ncols=len(uniq), fontsize=8)
    ax.set_title(f"{Path(str(spec.path)).name}: {h} x {w} cells of {house.grid.resolution:g} m "
                 f"(stars: sources; arrows: wind)", fontsize=9)
    # sources first; no label over another, over a source's star or over the start
    declutter(ax, labels + [t for t in ax.texts if t not in labels], avoid=[*at, tuple(start)])
    return fig
