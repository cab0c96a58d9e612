"""The benchmark's report: survival per condition, RMST with intervals over houses, the primary comparison and the
costs of off-ontology sources and of a wrong or room-less ontology (``report.md``, ``summary.json``, figures).

Times to find are censored at the budget τ; every run is observed until it finds the source or τ, so the
restricted mean RMST(τ) of an arm is the mean of min(T, τ) over its episodes (:func:`psgsl_pgm.search.rmst`).
Intervals of RMSTs and ratios are :func:`psgsl_pgm.search._survival.nested_bootstrap` over houses, then the seeds
within each drawn house; a ratio of two arms is computed on the same resampled episodes (the arms are paired by
episode). The success rate's interval is the house-clustered Wilson interval
(:func:`psgsl_pgm.search._metrics.clustered_wilson`), never a point; ``summary.json`` also gives the Wilson
interval with the episodes as independent (``wilson95``).

**The primary comparison, declared before any run:** RMST(τ) of ``infotaxis`` with ``semantics+rooms`` divided by
RMST(τ) of ``infotaxis`` with ``olfaction`` alone, ``right-ontology``, over all episodes, with its 95 % interval
(:data:`PRIMARY`). Below 1: semantics and rooms find sources sooner. Every other number is secondary and
exploratory. A comparison on fewer than :data:`MIN_EPISODES` paired episodes is flagged in ``report.md``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..io._json import json_safe
from ._metrics import clustered_wilson, declaration_summary, wilson_interval
from ._store import load_search_run
from ._survival import kaplan_meier, km_median, nested_bootstrap, rmst

__all__ = ["MIN_EPISODES", "PRIMARY", "write_report"]

#: The benchmark's primary comparison (module docstring): arm A over arm B in one condition.
PRIMARY = {"condition": "right-ontology", "A": "infotaxis/semantics+rooms", "B": "infotaxis/olfaction",
           "statistic": "RMST ratio A / B", "level": 0.95}
#: Below this many paired episodes report.md warns that a comparison's interval rests on few episodes.
MIN_EPISODES = 20
_SHARED = ("olfaction",)  # variants whose runs every condition shares with right-ontology (and the tour)


def _table(out: Path, settings: dict) -> list:
    """Rows ``{house, seed, condition, arm, found, t, kind}`` of the stored runs the settings select; runs the
    conditions share (tour, olfaction) appear under every condition."""
    rows = []
    keep_h, keep_s = set(settings["houses"]), set(settings["seeds"])
    for f in sorted((out / "runs").glob("*.npz")):
        r = load_search_run(f)
        b = r.config.get("benchmark") or {}
        if b.get("house") not in keep_h or r.seed not in keep_s or r.policy not in settings["policies"] \
                or r.variant not in settings["variants"] or r.estimator != settings["estimator"]:
            continue
        conds = [b["condition"]]
        if b["condition"] == "right-ontology" and (r.policy == "tour" or r.variant in _SHARED):
            conds = list(settings["conditions"])
        arm = "tour" if r.policy == "tour" else f"{r.policy}/{r.variant}"
        for c in conds:
            if c in settings["conditions"]:
                rows.append({"house": b["house"], "seed": r.seed, "condition": c, "arm": arm,
                             "found": bool(r.succeeded), "t": min(float(r.time_to_success), settings["budget"]),
                             "declared": bool(r.declared), "correct": bool(r.declared_correct),
                             "error": float(r.declared_error), "end": r.end,
                             "reached": bool(r.found), "t_reach": min(float(r.time_to_find), settings["budget"]),
                             "kind": b["episode"]["kind"],
                             "class": b["episode"]["class"], "gas": b["episode"]["gas"],
                             "cpu": b.get("cpu_seconds")}
                            | ({"gas_identified": r.gas_identified, "time_to_gas": r.time_to_gas()}
                               if r.gas_unknown else {})
                            | ({"several": _several_row(r, settings["budget"])}
                               if settings.get("sources_per_episode") else {}))
    return rows


def _arm_order(arm: str):
    from ..experiment._config import VARIANTS
    from ._policies import POLICIES

    policy, _, variant = arm.partition("/")
    return (POLICIES.index(policy), VARIANTS.index(variant) if variant else -1)


def _select(rows, **eq):
    return [r for r in rows if all(r[k] == v for k, v in eq.items())]


def _arm_stats(rows, tau: float) -> dict:
    t = np.array([r["t"] for r in rows])
    found = np.array([r["found"] for r in rows])
    km = kaplan_meier(t, found)
    houses = [r["house"] for r in rows]
    boot = nested_bootstrap(t, houses)
    success = clustered_wilson(found, houses)
    return {"n": len(rows), "houses": boot["groups"],
            "success_rate": {"value": success["value"], "ci95": success["ci95"],
                             "design_effect": success["design_effect"], "interval": success["interval"],
                             "wilson95": wilson_interval(int(found.sum()), len(rows))},
            "rmst": {"value": boot["value"], "ci95": boot["ci95"], "tau": tau, "interval": boot["interval"]},
            "median": km_median(km), "km": km, "cpu_seconds": _mean_cpu(rows),
            **(declaration_summary([r["declared"] for r in rows], [r["correct"] for r in rows],
                                   [r["error"] for r in rows], groups=houses)
               if all(r.get("end") == "declare" for r in rows) else {}),
            **({"reach": {"success_rate": float(np.mean([r["reached"] for r in rows])),
                          "rmst": float(np.mean([r["t_reach"] for r in rows])),
                          "note": "secondary: the first pass within the found radius of the source"}}
               if all("reached" in r for r in rows) else {}),
            **(_gas_stats(rows, tau) if rows and all("gas_identified" in r for r in rows) else {}),
            **(_several_stats(rows, tau) if rows and all("several" in r for r in rows) else {})}


def _several_row(r, budget: float) -> dict:
    """A run's several-source outcome: per-source times and events (censored at the budget), "all found", the
    declarations and the false ones."""
    t, ok = r.source_times()
    t_all, all_ok = r.time_to_all()
    n_decl = len(r.declarations) if len(r.declarations) else int(r.declared)
    return {"n_sources": r.n_sources, "t": np.minimum(t, budget).tolist(), "ok": ok.tolist(),
            "t_all": min(t_all, budget), "all": bool(all_ok), "declarations": n_decl,
            "false": r.n_false_declarations}


def _several_stats(rows, tau: float) -> dict:
    """Per source and for "all found" (:mod:`psgsl_pgm.search._several`): success (house-clustered Wilson 95 %),
    time (RMST with KM, censored at τ), and the false declarations; split by the number of sources."""
    def block(rs) -> dict:
        houses = [r["house"] for r in rs]
        t = np.concatenate([r["several"]["t"] for r in rs])
        ok = np.concatenate([r["several"]["ok"] for r in rs]).astype(bool)
        src_houses = [h for r, h in zip(rs, houses) for _ in r["several"]["t"]]
        per = clustered_wilson(ok, src_houses)
        t_all = np.array([r["several"]["t_all"] for r in rs])
        all_ok = np.array([r["several"]["all"] for r in rs], dtype=bool)
        every = clustered_wilson(all_ok, houses)
        n_decl = int(sum(r["several"]["declarations"] for r in rs))
        n_false = int(sum(r["several"]["false"] for r in rs))
        return {"n": len(rs), "sources": int(ok.size),
                "source_success": {"value": per["value"], "ci95": per["ci95"]},
                "source_rmst": {k: v for k, v in rmst(t, ok, tau).items() if k in ("value", "ci95")} | {"tau": tau},
                "all_found": {"value": every["value"], "ci95": every["ci95"]},
                "all_found_rmst": {k: v for k, v in rmst(t_all, all_ok, tau).items() if k in ("value", "ci95")}
                | {"tau": tau},
                "declarations": n_decl, "false_declarations": n_false,
                "false_declarations_per_run": n_false / len(rs),
                "false_declaration_rate": ({"value": n_false / n_decl, "ci95": wilson_interval(n_false, n_decl)}
                                           if n_decl else None)}

    counts = sorted({r["several"]["n_sources"] for r in rows})
    out = block(rows)
    if len(counts) > 1:
        out["by_count"] = {str(n): block([r for r in rows if r["several"]["n_sources"] == n]) for n in counts}
    return {"several_sources": out}


def _gas_stats(rows, tau: float) -> dict:
    """``gas_identified`` (most probable gas at the end = the true one; Wilson 95 %) and ``time_to_gas`` (RMST of
    the time until p(true gas | e-nose readings) ≥ 0.9, censored at τ) of runs whose gas the robot was not told."""
    ok = np.array([r["gas_identified"] for r in rows])
    t = np.array([min(r["time_to_gas"][0], tau) for r in rows])
    reached = np.array([r["time_to_gas"][1] for r in rows])
    area = rmst(t, reached, tau)
    return {"gas_identified": {"value": float(ok.mean()), "ci95": wilson_interval(int(ok.sum()), len(rows))},
            "time_to_gas": {"value": area["value"], "ci95": area["ci95"], "tau": tau, "level": 0.9,
                            "reached": int(reached.sum())}}


def _reached(d) -> str:
    return f"{100 * d['reach']['success_rate']:.0f} %" if "reach" in d else "—"


def _mean_cpu(rows):
    cpu = [r["cpu"] for r in rows if r["cpu"] is not None]
    return float(np.mean(cpu)) if cpu else None


def _paired(rows_a, rows_b):
    a = {(r["house"], r["seed"]): r for r in rows_a}
    b = {(r["house"], r["seed"]): r for r in rows_b}
    keys = sorted(set(a) & set(b))
    return keys, np.array([[a[k]["t"] for k in keys], [b[k]["t"] for k in keys]])


def _ratio(rows_a, rows_b) -> dict | None:
    keys, v = _paired(rows_a, rows_b)
    if len(keys) < 2 or v[1].sum() <= 0:
        return None
    boot = nested_bootstrap(v, [k[0] for k in keys], lambda x: x[0].mean() / x[1].mean())
    return {"value": boot["value"], "ci95": boot["ci95"], "n": len(keys), "houses": boot["groups"],
            "rmst_A": float(v[0].mean()), "rmst_B": float(v[1].mean()), "interval": boot["interval"]}


def _comparisons(rows, conditions) -> dict:
    """The primary comparison and the costs beside it."""
    a, b, main = PRIMARY["A"], PRIMARY["B"], PRIMARY["condition"]
    out = {"primary": None, "costs": {}}
    right = _select(rows, condition=main)
    out["primary"] = _ratio(_select(right, arm=a), _select(right, arm=b))
    for kind in ("object", "off-ontology"):
        sub = _select(right, kind=kind)
        out["costs"][f"primary ratio, {kind} sources only"] = _ratio(_select(sub, arm=a), _select(sub, arm=b))
    for c in conditions:
        if c == main:
            continue
        rows_c = _select(rows, condition=c)
        out["costs"][f"primary ratio under {c}"] = _ratio(_select(rows_c, arm=a), _select(rows_c, arm=b))
        out["costs"][f"{a}: RMST {c} / {main}"] = _ratio(_select(rows_c, arm=a), _select(right, arm=a))
    return out


def _fmt_ci(d, unit="", digits=1):
    if d is None:
        return "n/a (an arm not run, or fewer than 2 paired episodes)"
    lo, hi = d["ci95"]
    return f"{d['value']:.{digits}f}{unit} [{lo:.{digits}f}, {hi:.{digits}f}]"


def _few(name: str, d) -> list:
    """The one-line warning of a comparison on fewer than :data:`MIN_EPISODES` paired episodes (else none)."""
    if d is None or d["n"] >= MIN_EPISODES:
        return []
    return [f"Warning: {name} rests on {d['n']} paired episodes (fewer than {MIN_EPISODES}); its interval is "
            "unreliable.", ""]


def _figures(out: Path, stats: dict, conditions) -> list:
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    files = []
    arms = sorted(dict.fromkeys(a for c in conditions for a in stats[c]), key=_arm_order)
    colour = {a: f"C{i % 10}" for i, a in enumerate(arms)}  # one colour per arm in every panel
    entry = 0.6 + 0.075 * max(len(a) for a in arms)  # legend entry width (in) at 9 pt: line, gap, label
    width = max(5 * len(conditions), min(12.5, 2 * entry))  # at most 12.5 in: legible in the docs' column
    ncols = max(1, min(len(arms), int(width // entry)))  # the legend wraps instead of running off the figure
    rows = -(-len(arms) // ncols)
    fig, axes = plt.subplots(1, len(conditions), figsize=(width, 4.2 + 0.22 * rows), squeeze=False, sharey=True,
                             layout="constrained")
    for ax, c in zip(axes[0], conditions):
        for arm, s in stats[c].items():
            ax.step(s["km"]["t"], s["km"]["survival"], where="post", label=arm, color=colour[arm])
        ax.set_title(c)
        ax.set_xlabel("time (s)")
        ax.set_ylim(0, 1.02)
    axes[0][0].set_ylabel("P(no success by t)")
    handles = [plt.Line2D([], [], color=colour[a]) for a in arms]  # below the panels: no curve hidden
    fig.legend(handles, arms, loc="outside lower center", ncols=ncols, fontsize=9, frameon=False)
    fig.savefig(out / "survival.png", dpi=110)
    plt.close(fig)
    files.append("survival.png")
    fig, ax = plt.subplots(figsize=(max(6, 1.2 * len(arms)), 4))
    width = 0.8 / len(conditions)
    for j, c in enumerate(conditions):
        xs, ys, lo, hi = [], [], [], []
        for i, a in enumerate(arms):
            if a in stats[c]:
                r = stats[c][a]["rmst"]
                xs.append(i + (j - (len(conditions) - 1) / 2) * width)
                ys.append(r["value"])
                lo.append(r["value"] - r["ci95"][0])
                hi.append(r["ci95"][1] - r["value"])
        ax.bar(xs, ys, width, yerr=[lo, hi], capsize=3, label=c)
    ax.set_xticks(range(len(arms)), arms, rotation=25, ha="right", fontsize=8)
    ax.set_ylabel("RMST(τ) (s), 95 % nested bootstrap")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "rmst.png", dpi=110)
    plt.close(fig)
    files.append("rmst.png")
    return files


def _several_table(arms: dict) -> list:
    """The several-source table of a condition (empty in a one-source benchmark)."""
    rows = [(a, d["several_sources"]) for a, d in arms.items() if "several_sources" in d]
    if not rows:
        return []
    lines = ["Several sources per episode (the robot declares them one by one, psgsl_pgm.search._several): "
             "per source and for all of an episode's sources, success (house-clustered Wilson 95 %) and RMST(τ) "
             "of the time (KM, censored at τ; per source, its declaration; all, the last of them); false "
             "declarations per run. The success and RMST above are those of the first source declared.", "",
             "| arm | N | episodes | sources | source success [95 % CI] | source RMST s | all found [95 % CI] | "
             "all-found RMST s | false decl. / run |", "|---|---|---|---|---|---|---|---|---|"]
    for arm, d in rows:
        parts = [("all", d)] + sorted((d.get("by_count") or {}).items())
        for n, b in parts:
            ss, af = b["source_success"], b["all_found"]
            lines.append(f"| {arm} | {n} | {b['n']} | {b['sources']} | {100 * ss['value']:.0f} % "
                         f"[{100 * ss['ci95'][0]:.0f}, {100 * ss['ci95'][1]:.0f}] | {_fmt_ci(b['source_rmst'])} | "
                         f"{100 * af['value']:.0f} % [{100 * af['ci95'][0]:.0f}, {100 * af['ci95'][1]:.0f}] | "
                         f"{_fmt_ci(b['all_found_rmst'])} | {b['false_declarations_per_run']:.2f} |")
    return lines + [""]


def _markdown(settings: dict, stats: dict, comp: dict, episodes: dict, files, version: str) -> str:
    s = settings
    title = "world file " + s["world"] if s["world"] else f"{len(s['houses'])} generated homes"
    lines = [f"# psgsl benchmark: {title}", ""]
    if s.get("command"):
        lines += [f"Command: `{s['command']}`", ""]
    split = s.get("split", "dev")
    what = "test homes and seeds, run once per release" if split == "test" else "development homes and seeds"
    lines += [f"Split: **{split}** ({what}).", "",
              f"psgsl-pgm {version}; houses {', '.join(s['houses'][:6])}{' …' if len(s['houses']) > 6 else ''} "
              f"({len(s['houses'])}); seeds {s['seeds'][0]}–{s['seeds'][-1]}; budget τ = {s['budget']:g} s; "
              f"estimator {s['estimator']}; gases {', '.join(s['gases'])}; off-ontology rate {s['off_rate']:g}.",
              "", "## Primary comparison (declared before the runs)", "",
              f"{PRIMARY['statistic']}, A = `{PRIMARY['A']}`, B = `{PRIMARY['B']}`, condition `{PRIMARY['condition']}`, "
              "all episodes; 95 % nested percentile bootstrap (houses, then seeds within a house; one world file: "
              "seeds), paired by episode. "
              "Below 1: A succeeds sooner. Success: a declaration within 1 m of the source (the run ends at the "
              "robot's first declaration; a wrong one is a failure).", ""]
    p = comp["primary"]
    lines += [f"**{_fmt_ci(p, digits=3)}**" + (f" (n = {p['n']} episodes in {p['houses']} houses; RMST A "
                                                f"{p['rmst_A']:.1f} s, B {p['rmst_B']:.1f} s)" if p else ""), ""]
    lines += _few("the primary comparison", p)
    lines += ["## Costs beside it (secondary, exploratory)", "",
              "Exploratory: not declared before the runs and not corrected for multiplicity; they suggest, they do "
              "not confirm.", "", "| comparison | ratio [95 % CI] | n |", "|---|---|---|"]
    few = []
    for name, d in comp["costs"].items():
        lines.append(f"| {name} | {_fmt_ci(d, digits=3)} | {d['n'] if d else 0} |")
        few += _few(f"'{name}'", d)
    lines += [""] + few
    lines += ["Off-ontology: the primary ratio on the episodes whose source is a floor cell no ontology class "
              "holds, beside the ratio on object sources. Wrong ontology: p(o | s, γ) permuted among the object "
              "classes per house (a derangement); no rooms: no p(o | room). `tour` and the `olfaction` variant do "
              "not read the ontology: their runs are shared by every condition.", ""]
    for c, arms in stats.items():
        lines += [f"## {c}", "", "Success: house-clustered Wilson 95 % interval; RMST of the time to success: nested "
                  "bootstrap; false declarations: wrong of those made (Wilson); declared error: median and 90th "
                  "percentile over the declarations; reached: the secondary rate of passing within the found radius.",
                  "", "| arm | n | houses | success [95 % CI] | RMST(τ) s [95 % CI] | KM median s | false decl. | "
                  "decl. error m (median, q90) | reached | CPU s/run |", "|---|---|---|---|---|---|---|---|---|---|"]
        for arm, d in arms.items():
            sr = d["success_rate"]
            med = "—" if d["median"] is None else f"{d['median']:.1f}"
            cpu = "—" if d["cpu_seconds"] is None else f"{d['cpu_seconds']:.1f}"
            fd, de = d.get("false_declaration_rate"), d.get("declared_error")
            fds = "—" if fd is None else f"{100 * fd['value']:.0f} % of {fd['n']}"
            des = "—" if de is None else f"{de['median']:.2f}, {de['q90']:.2f}"
            lines.append(f"| {arm} | {d['n']} | {d['houses']} | {100 * sr['value']:.0f} % "
                         f"[{100 * sr['ci95'][0]:.0f}, {100 * sr['ci95'][1]:.0f}] | {_fmt_ci(d['rmst'])} | {med} | "
                         f"{fds} | {des} | {_reached(d)} | {cpu} |")
        lines.append("")
        lines += _several_table(arms)
    kinds: dict = {}
    for e in episodes.values():
        k = e["class"] or "off-ontology"
        kinds[k] = kinds.get(k, 0) + 1
    lines += ["## Episodes", "", ", ".join(f"{k} {v}" for k, v in sorted(kinds.items(), key=lambda kv: -kv[1])), ""]
    lines += ["## Figures", ""] + [f"![{f}]({f})" for f in files] + [""]
    return "\n".join(lines)


def write_report(out, settings: dict, *, figures: bool = True) -> dict:
    """Aggregate the stored runs the ``settings`` select into ``out/report.md``, ``out/summary.json`` and the
    figures ``survival.png`` (Kaplan–Meier per condition) and ``rmst.png``; returns the summary."""
    from .. import __version__
    from ..io._output import write_file_atomically

    out = Path(out)
    rows = _table(out, settings)
    if not rows:
        raise ValueError(f"no benchmark runs stored in {out / 'runs'} for these settings")
    tau = float(settings["budget"])
    conditions = [c for c in settings["conditions"] if _select(rows, condition=c)]
    stats = {}
    for c in conditions:
        arms = sorted(dict.fromkeys(r["arm"] for r in _select(rows, condition=c)), key=_arm_order)
        stats[c] = {a: _arm_stats(_select(rows, condition=c, arm=a), tau) for a in arms}
    comp = _comparisons(rows, conditions)
    episodes = json.loads((out / "episodes.json").read_text()) if (out / "episodes.json").exists() else {}
    episodes = {k: v for k, v in episodes.items()
                if k.split("/")[0] in settings["houses"] and int(k.split("/")[1]) in settings["seeds"]}
    files = _figures(out, stats, conditions) if figures else []
    summary = {"settings": settings, "version": __version__, "primary": PRIMARY | {"result": comp["primary"]},
               "costs": comp["costs"], "arms": stats}
    text = json.dumps(json_safe(summary), indent=1, sort_keys=True, allow_nan=False) + "\n"
    write_file_atomically(out / "summary.json", lambda fh: fh.write(text.encode("utf-8")))
    md = _markdown(settings, stats, comp, episodes, files, __version__)
    write_file_atomically(out / "report.md", lambda fh: fh.write(md.encode("utf-8")))
    return summary
