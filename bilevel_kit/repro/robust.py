"""``bilevel-kit repro robust``: does planning for the spread of human times pay (issue 41,
docs/robust.md)?

For each instance (the paper's table, ``instances/hrc_table.json``, and a 12-task KitBench
instance), tray count (1, 2, unlimited) and coefficient of variation ``cv`` of every human
time (:mod:`bilevel_kit.stochastic`: independent lognormal per task), one cell:

1. the **mean-value plan**: the exact SAA model (:mod:`bilevel_kit.models.cpsat.saa`) with the
   one scenario of the mean times, i.e. the deterministic problem;
2. the **SAA plan**: the same model on ``scenarios`` scenarios of the ``OPTIMISE`` stream,
   hinted with the mean-value plan (never worse in-sample);
3. both plans on ``evaluation`` (>= 1,000) scenarios of the independent ``EVALUATE`` stream:
   each plan's expected makespan with its 95 % interval and the **VSS** (value of the
   stochastic solution) = E[mean-value plan] - E[SAA plan], a paired interval on the same
   scenarios (common random numbers);
4. **EVPI** (expected value of perfect information) = E[SAA plan] - E[wait-and-see], on
   ``wait_and_see`` scenarios of the ``WAIT_AND_SEE`` stream, each solved alone by the same
   model: the per-scenario plans found give the ``evpi`` estimate (a lower estimate when a
   scenario is not proven), their bounds the ``evpi_high`` one (an upper estimate).

Every solve is limited by CP-SAT's deterministic time with one worker, so a cell is a pure
function of (config, seed) (bilevel_kit/experiments/cells.py) as long as the wall-clock
safety net (:data:`SAFETY_S` per solve) does not fire. On a heavily loaded machine it can cut a
solve short (a worse SAA plan, a weaker ``saa_bound``, ``saa_proven`` false; docs/robust.md),
so each cell counts the solves it cut (``safety_net_fired``); :func:`run_robust` computes such
a cell once more, alone, and a cell still cut keeps its count in the CSV, never passed off as
reproducible. Writes ``robust.csv``, ``robust.md``,
``robust.png`` (VSS against cv per tray count, :func:`plot_robust_panel`) and
``robust.json``.
"""

from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import atomic, style
from ..errors import UsageError
from ..experiments.tables import markdown_lines, write_csv
from ..instance import Instance, from_dict
from ..plan import Kit, Plan
from ..stochastic import EVALUATE, OPTIMISE, WAIT_AND_SEE, estimate, makespans, paired, sample

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

ROOT = Path(__file__).resolve().parents[2]
#: The study's instances: name -> file (the paper's table and a 12-task KitBench instance).
INSTANCES = {
    "table": "instances/hrc_table.json",
    "sp12": "instances/kitbench/sp_n12_s1_t1_tight_d10.json",
}
CVS = (0.1, 0.2, 0.3, 0.5)
#: Tray counts; None: unlimited.
TRAYS: tuple[int | None, ...] = (1, 2, None)
#: Scenarios optimised on, evaluated on and solved one by one (wait-and-see).
SCENARIOS, EVALUATION, WAIT_AND_SEE_N = 10, 1000, 5
#: CP-SAT deterministic time of the mean-value, SAA and each wait-and-see solve.
DET_MEAN, DET_SAA, DET_WS = 2.0, 5.0, 0.3
#: Wall-clock safety net of every solve (s), for a hung solve only (docs/robust.md#the-study):
#: the slowest solves, the table's SAA ones, took about 11 s on the idle 2-core machine and 28 s
#: in the study run with ``--jobs 2`` beside other work, so it fires only under a load that
#: slows a solve down over twentyfold (the first committed run's, a load average near 28 on 2
#: cores, cut solves at 120 s). Any value of 40 s or more gives the same packing limits
#: (:func:`..models.common.pack_time_limit`), hence the same cells.
SAFETY_S = 300.0


def tray_label(trays: int | None) -> str:
    return "unlimited" if trays is None else str(trays)


def study_instance(name: str, trays: int | None) -> Instance:
    """Instance ``name`` of :data:`INSTANCES` with ``trays`` trays (None: unlimited)."""
    path = ROOT / INSTANCES[name]
    doc = json.loads(path.read_text())
    doc.pop("trays", None)
    if trays is not None:
        doc["trays"] = trays
    return from_dict(doc, f"<robust study {name}, trays {tray_label(trays)}>")


@dataclass(frozen=True)
class RobustCell:
    """One (instance, trays, cv, seed) point of the study (module docstring)."""

    instance: str
    trays: int | None
    cv: float
    seed: int
    scenarios: int = SCENARIOS
    evaluation: int = EVALUATION
    wait_and_see: int = WAIT_AND_SEE_N
    #: the instance file's digest (:func:`.common.file_digest`): a changed file is a new cell
    digest: str = ""

    def key(self) -> str:
        return cell_key(self)


def cell_key(cell: Any) -> str:
    """A robust (or robust-sim) cell's file key: its coordinates and a digest of every field,
    so a changed setting is a new cell."""
    blob = json.dumps(asdict(cell), sort_keys=True).encode()
    digest = hashlib.sha1(blob).hexdigest()[:10]
    return f"{cell.instance}_t{tray_label(cell.trays)}_cv{cell.cv}_{cell.seed}__{digest}"


def _solve(inst: Instance, scenarios: np.ndarray, det: float, start: Plan | None = None) -> Any:
    """The SAA model within ``det`` deterministic time (one worker) and :data:`SAFETY_S`;
    its ``info`` gets the solve's wall time (``solve_wall_s``) beside ``saa_safety_net``."""
    from ..models.cpsat.saa import solve_saa

    t0 = time.perf_counter()
    out = solve_saa(
        inst, scenarios, time_limit=SAFETY_S, start=start, deterministic_time=det, workers=1
    )
    out.info["solve_wall_s"] = time.perf_counter() - t0
    return out


def _plan(out: Any) -> Plan:
    return Plan(tuple(Kit(k) for k in out.kits))


def study_solves(
    inst: Instance, cv: float, seed: int, scenarios: int = SCENARIOS, start: Plan | None = None
) -> tuple[Any, Any, np.ndarray]:
    """A cell's mean-value and SAA solves (module docstring, steps 1-2) and the SAA's
    ``OPTIMISE`` scenarios; the SAA solve is hinted with the mean-value plan's task lists, the
    mean-value solve with ``start`` (e.g. a KitBench record's best-known plan), if given."""
    means = np.array([[t.human_mean for t in inst.tasks]])
    mean_out = _solve(inst, means, DET_MEAN, start=start)
    opt = sample(inst, scenarios, seed, cv=cv, stream=OPTIMISE)
    saa_out = _solve(inst, opt, DET_SAA, start=_plan(mean_out))
    return mean_out, saa_out, opt


def robust_cell(cell: RobustCell) -> dict[str, Any]:
    """The cell's plans and estimates (module docstring)."""
    t0 = time.process_time()
    return cell_estimates(cell, study_instance(cell.instance, cell.trays), t0)


def cell_estimates(
    cell: Any, inst: Instance, t0: float, start: Plan | None = None
) -> dict[str, Any]:
    """Steps 1-4 of the module docstring on ``inst`` for ``cell`` (a :class:`RobustCell` or a
    dataclass with its fields, e.g. :mod:`.robust_kitbench`'s), the mean-value solve hinted
    with ``start``; ``cpu_s`` counted from ``t0`` (:func:`time.process_time`)."""
    mean_out, saa_out, opt = study_solves(inst, cell.cv, cell.seed, cell.scenarios, start)
    mean_plan, saa_plan = _plan(mean_out), _plan(saa_out)
    ev = sample(inst, cell.evaluation, cell.seed, cv=cell.cv, stream=EVALUATE)
    a, b = makespans(inst, mean_plan, ev), makespans(inst, saa_plan, ev)
    ws = sample(inst, cell.wait_and_see, cell.seed, cv=cell.cv, stream=WAIT_AND_SEE)
    per = [_solve(inst, row[None, :], DET_WS, start=saa_plan) for row in ws]
    own = makespans(inst, saa_plan, ws)
    out: dict[str, Any] = {"key": cell.key(), "cell": asdict(cell)}
    for name, est in (
        ("mean_plan", estimate(a)),
        ("saa_plan", estimate(b)),
        ("vss", paired(a, b)),
        ("evpi", paired(own, [o.value for o in per])),
        ("evpi_high", paired(own, [o.bound if o.bound is not None else 0.0 for o in per])),
    ):
        out.update({name: est.mean, f"{name}_low": est.low, f"{name}_high": est.high})
    out.update(
        mean_plan_deterministic=mean_out.value,
        mean_plan_proven=mean_out.proven,
        saa_in_sample=saa_out.value,
        saa_bound=saa_out.bound,
        saa_proven=saa_out.proven,
        mean_plan_in_sample=float(makespans(inst, mean_plan, opt).mean()),
        same_plan=[set(k) for k in saa_out.kits] == [set(k) for k in mean_out.kits],
        ws_proven=sum(o.proven for o in per),
        mean_kits=len(mean_out.kits),
        saa_kits=len(saa_out.kits),
        cpu_s=time.process_time() - t0,
    )
    solves = (mean_out, saa_out, *per)
    out.update(  # the safety net (module docstring) and what the solves took
        safety_net_fired=sum(bool(o.info["saa_safety_net"]) for o in solves),
        solve_wall_s=[o.info["solve_wall_s"] for o in solves],
        solve_det=[o.info["saa_deterministic_time"] for o in solves],
    )
    return out


#: The CSV's columns, in order.
COLUMNS = (
    "instance", "trays", "cv", "seed", "mean_plan", "mean_plan_low", "mean_plan_high",
    "saa_plan", "saa_plan_low", "saa_plan_high", "vss", "vss_low", "vss_high", "vss_pct",
    "evpi", "evpi_low", "evpi_high", "mean_plan_deterministic", "mean_plan_proven",
    "mean_plan_in_sample", "saa_in_sample", "saa_bound", "saa_proven", "same_plan",
    "ws_proven", "mean_kits", "saa_kits", "safety_net_fired",
)  # fmt: skip


def rows_of(records: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """One CSV row per cell, numbers rounded to what the intervals can tell (0.01 s)."""
    out = []
    for r in records:
        row: dict[str, Any] = {**r["cell"], **r}
        row["trays"] = tray_label(r["cell"]["trays"])
        row["vss_pct"] = 100.0 * r["vss"] / r["mean_plan"]
        row["evpi_high"] = r["evpi_high_high"]  # the upper end of the upper estimate
        out.append(
            {
                k: round(float(row[k]), 3 if k == "vss_pct" else 2)
                if isinstance(row[k], float)
                else row[k]
                for k in COLUMNS
            }
        )
    return out


def vss_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """VSS (s) [95 % paired interval] per instance and tray count (rows) and cv (columns)."""
    cvs = sorted({float(r["cv"]) for r in rows})
    keys = list(dict.fromkeys((str(r["instance"]), str(r["trays"])) for r in rows))
    by = {(str(r["instance"]), str(r["trays"]), float(r["cv"])): r for r in rows}
    head = ["instance", "trays", *(f"cv {c:g}" for c in cvs)]
    body = [
        [
            inst,
            trays,
            *(
                f"{float(by[(inst, trays, c)]['vss']):.2f} "
                f"[{float(by[(inst, trays, c)]['vss_low']):.2f}, "
                f"{float(by[(inst, trays, c)]['vss_high']):.2f}]"
                if (inst, trays, c) in by
                else "-"
                for c in cvs
            ),
        ]
        for inst, trays in keys
    ]
    return "\n".join(markdown_lines(head, body))


def detail_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """Per cell: both plans' expected makespans, VSS in % of the mean-value plan's, EVPI
    (lower and upper estimate) and whether the SAA plan differs."""
    head = ["instance", "trays", "cv", "E mean-value plan (s)", "E SAA plan (s)", "VSS (%)"]
    head += ["EVPI (s)", "EVPI upper (s)", "SAA plan differs"]
    body = [
        [
            str(r["instance"]),
            str(r["trays"]),
            f"{float(r['cv']):g}",
            f"{float(r['mean_plan']):.1f} ± {_half(r, 'mean_plan'):.1f}",
            f"{float(r['saa_plan']):.1f} ± {_half(r, 'saa_plan'):.1f}",
            f"{float(r['vss_pct']):.2f}",
            f"{float(r['evpi']):.1f}",
            f"{float(r['evpi_high']):.1f}",
            "no" if str(r["same_plan"]) in ("True", "true") else "yes",
        ]
        for r in rows
    ]
    return "\n".join(markdown_lines(head, body))


def _half(r: Mapping[str, Any], name: str) -> float:
    return (float(r[f"{name}_high"]) - float(r[f"{name}_low"])) / 2


@style.styled
def plot_robust_panel(
    rows: Sequence[Mapping[str, Any]], instance: str, *, ax: Axes | None = None
) -> Axes:
    """VSS (s) against cv for ``instance``, one line per tray count with its 95 % paired
    interval (error bars); 0 marked."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(4.4, 3.2), layout="constrained")
    mine = [r for r in rows if r["instance"] == instance]
    trays = list(dict.fromkeys(str(r["trays"]) for r in mine))
    for j, (t, sw) in enumerate(zip(trays, style.categorical(len(trays)), strict=True)):
        rs = sorted((r for r in mine if str(r["trays"]) == t), key=lambda r: float(r["cv"]))
        x = [float(r["cv"]) + 0.006 * (j - 1) for r in rs]  # side by side
        y = [float(r["vss"]) for r in rs]
        err = [
            [y_ - float(r["vss_low"]) for y_, r in zip(y, rs, strict=True)],
            [float(r["vss_high"]) - y_ for y_, r in zip(y, rs, strict=True)],
        ]
        ax.errorbar(x, y, yerr=err, marker="o", ms=3, capsize=2, color=sw.color, label=t)
    ax.axhline(0.0, color="black", lw=0.8)
    ax.set_xlabel("coefficient of variation of human times")
    ax.set_ylabel("VSS (s)")
    ax.set_title(instance)
    ax.legend(title="trays", fontsize="small")
    ax.grid(alpha=0.3)
    return ax


@style.styled
def plot_robust(rows: Sequence[Mapping[str, Any]]) -> Figure:
    """One :func:`plot_robust_panel` per instance, side by side."""
    import matplotlib.pyplot as plt

    names = list(dict.fromkeys(str(r["instance"]) for r in rows))
    fig, axes = plt.subplots(
        1, len(names), figsize=(4.2 * len(names), 3.4), squeeze=False, layout="constrained"
    )
    for name, ax in zip(names, axes[0], strict=True):
        plot_robust_panel(rows, name, ax=ax)
    return fig


def run_robust(
    out_dir: str | Path = "out/repro/robust",
    quick: bool = False,
    jobs: int = 1,
    seed: int = 0,
    *,
    instances: Sequence[str] | None = None,
    cvs: Sequence[float] | None = None,
    trays: Sequence[int | None] | None = None,
    progress: bool | None = None,
    **_: Any,
) -> dict[str, Any]:
    """The study (module docstring); ``quick``: the table only at cv 0.1 and 0.5. Cells are
    saved under ``out_dir/cells/`` (a rerun computes only the missing ones)."""
    t0 = time.perf_counter()
    names = tuple(instances) if instances else (("table",) if quick else tuple(INSTANCES))
    grid = tuple(cvs) if cvs else ((0.1, 0.5) if quick else CVS)
    tray_grid = tuple(trays) if trays else TRAYS
    bad = [n for n in names if n not in INSTANCES]
    if bad or min(grid) < 0:
        raise UsageError(f"bad robust study options {bad or grid}: instances from "
                         f"{', '.join(INSTANCES)}, cv >= 0")  # fmt: skip
    from .common import file_digest, run_study_cells, study_summary

    digests = {n: file_digest(ROOT / INSTANCES[n]) for n in names}
    cells = [
        RobustCell(n, t, c, seed, digest=digests[n]) for n in names for t in tray_grid for c in grid
    ]
    out = Path(out_dir)
    ran = run_study_cells(
        cells, robust_cell, out, jobs=jobs, progress=progress, desc="robust cells"
    )
    ran, retried = rerun_cut(cells, ran, out, progress)
    rows = rows_of(ran[0])
    files = _write_outputs(out, rows, quick)
    summary = study_summary(
        out, "robust", ran, rows, files, t0=t0, quick=quick, seed=seed, cells=len(cells)
    )
    walls = [w for r in ran[0] for w in r.get("solve_wall_s", [])]
    summary.update(
        retried=retried,
        cut=[r["key"] for r in ran[0] if r.get("safety_net_fired", 1)],
        slowest_solve_wall_s=max(walls, default=None),
    )
    from ..experiments.cells import write_json

    write_json(out / "robust.json", summary)
    return summary


def rerun_cut(
    cells: Sequence[Any], ran: Any, out: Path, progress: bool | None, fn: Any = robust_cell
) -> tuple[Any, list[str]]:
    """The sweep ``ran`` of cell function ``fn`` with every cell whose safety net fired (its
    saved record included: never reused as if reproducible) computed once more, alone
    (``jobs=1``: the least load this run adds), and the keys of those cells. A cell cut again
    keeps its count."""
    from ..experiments.cells import cell_file
    from .common import run_study_cells

    ok, failed, computed = ran
    cut = {r["key"] for r in ok if r.get("safety_net_fired", 1)}  # unrecorded: as if cut
    if not cut:
        return ran, []
    again = [c for c in cells if c.key() in cut]
    for c in again:
        cell_file(out / "cells", c.key()).unlink(missing_ok=True)
    ok2, failed2, computed2 = run_study_cells(
        again, fn, out, jobs=1, progress=progress, desc="robust cells cut, again"
    )
    by_key = {r["key"]: r for r in ok if r["key"] not in cut}
    by_key.update((r["key"], r) for r in ok2)
    merged = [by_key[c.key()] for c in cells if c.key() in by_key]
    return (merged, [*failed, *failed2], computed + computed2), sorted(cut)


def _write_outputs(out: Path, rows: Sequence[Mapping[str, Any]], quick: bool) -> dict[str, Path]:
    from ..plots import save_figure

    head = (
        f"Robust planning{' (QUICK: a reduced run)' if quick else ''}: VSS (s) = E[mean-value "
        f"plan] - E[SAA plan] on {EVALUATION} evaluation scenarios, mean [95 % paired "
        "interval].\n\n"
    )
    files: dict[str, Path] = {
        "csv": write_csv(out / "robust.csv", rows, exclude=(), line_end="\n"),
        "markdown": out / "robust.md",
    }
    body = vss_markdown(rows) + "\n\n" + detail_markdown(rows) + "\n"
    atomic.write_text(files["markdown"], head + body)
    files["figure"] = save_figure(plot_robust(rows), out / "robust.png")
    return files
