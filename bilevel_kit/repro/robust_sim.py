"""``bilevel-kit repro robust-sim``: the robust study's plans in the shop-floor simulation, and
the online policies beside them (issue 41; docs/robust.md#in-the-shop-floor-simulation).

For each cell (instance, trays, cv) of the robust study (:mod:`.robust`):

1. the **mean-value plan** and the **SAA plan** are recomputed exactly as the study computes
   them (the same model, scenarios, deterministic time limits and one worker: a pure function
   of the cell and its seed) and judged again on the study's 1,000 evaluation scenarios; the
   CSV says whether that reproduces the committed ``robust.csv`` (``reproduced``);
2. both plans run in the simulator as the ``fixed-plan`` policy (:mod:`bilevel_kit.sim.fixed`:
   the kits in their order, never re-planned), and the online policies ``cpsat-rolling`` and
   ``optimized-adaptive`` run beside them, all on the same replication seeds ``0 .. R-1``
   (common random numbers: every policy meets the same human times), without feeders (every
   part in stock, as in the timeline) and with deterministic robot times;
3. human times come from the simulator's own human model (:class:`~bilevel_kit.sim.TimingModel`,
   ``mean_i * s * e_i``) at the cell's CV, under two laws:

   * ``task``: independent per-task noise ``e_i`` of CV ``cv``, no participant factor
     (``participant_cv = 0, task_cv = cv``): the timeline study's own law, so the simulated
     VSS must agree with the timeline's within the intervals (a check of the whole chain);
   * ``participant``: one speed factor ``s`` of CV ``cv`` for every task of the unit, no
     per-task noise (``participant_cv = cv, task_cv = 0``): the shape of the simulator's
     default model (the paper's per-table SD comes from participants), which the SAA plan
     was not optimised for.

The simulated VSS is E[mean-value plan] - E[SAA plan] over the R replications, with its 95 %
paired interval; each online policy's gain over the mean-value plan likewise. An online policy
that fails in a cell (as ``cpsat-rolling`` did on ``sp12`` before it took the packing
oracle's layouts, docs/simulation.md#layouts-of-committed-kits) is a row with its ``error``
and no numbers, not a failed cell: the fixed plans' comparison still stands.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import atomic
from ..errors import KitDoesNotFit, UsageError, one_line
from ..experiments.tables import markdown_lines, write_csv
from ..instance import Instance
from ..plan import Kit, Plan
from ..stochastic import EVALUATE, OPTIMISE, estimate, makespans, paired, sample
from .robust import (
    CVS,
    EVALUATION,
    INSTANCES,
    ROOT,
    SCENARIOS,
    TRAYS,
    cell_key,
    study_instance,
    study_solves,
    tray_label,
)

#: The cells run by default: every cell of the study (:mod:`.robust`: both instances, 1, 2
#: and unlimited trays, every cv; issue 41), the order of ``robust.csv``.
CELLS: tuple[tuple[str, int | None, float], ...] = tuple(
    (n, t, c) for n in INSTANCES for t in TRAYS for c in CVS
)
QUICK_CELLS: tuple[tuple[str, int | None, float], ...] = (("table", 1, 0.5),)
#: Replications per cell and law (``--reps``); 5 with ``--quick``.
REPS, QUICK_REPS = 30, 5
#: The human-time laws (module docstring).
LAWS = ("task", "participant")
#: The policies, in the CSV's order: the two fixed plans, then the online ones.
FIXED = ("mean-plan", "saa-plan")
ONLINE = ("cpsat-rolling", "optimized-adaptive")
#: The committed timeline study the recomputed plans are compared with.
COMMITTED = ROOT / "paper_repro" / "results" / "robust.csv"


@dataclass(frozen=True)
class RobustSimCell:
    """One (instance, trays, cv, seed) cell of the robust study, ``reps`` replications."""

    instance: str
    trays: int | None
    cv: float
    seed: int
    reps: int = REPS
    #: the instance file's digest (:func:`.common.file_digest`): a changed file is a new cell
    digest: str = ""

    def key(self) -> str:
        return cell_key(self)


def select_cells(
    instances: Sequence[str] | None = None,
    trays: Sequence[int | None] | None = None,
    cvs: Sequence[float] | None = None,
) -> tuple[tuple[str, int | None, float], ...]:
    """Every (instance, trays, cv) of the given lists (``--instances``, ``--trays``,
    ``--cvs``), each left out meaning the robust study's own (:mod:`.robust`)."""
    names = tuple(instances or INSTANCES)
    unknown = [n for n in names if n not in INSTANCES]
    if unknown:
        raise UsageError(
            f"robust-sim: unknown instance {unknown[0]!r}; the study's are {', '.join(INSTANCES)}"
        )
    return tuple((n, t, float(c)) for n in names for t in (trays or TRAYS) for c in (cvs or CVS))


def study_plans(instance: Instance, cv: float, seed: int) -> tuple[Plan, Plan]:
    """The robust study's mean-value and SAA plans of a cell (docs/robust.md#the-study): the
    same model, scenarios and deterministic limits as :func:`.robust.robust_cell`, each kit
    with the packing oracle's layout (the simulator checks them; the timeline ignores them)."""
    mean_out, saa_out, _ = study_solves(instance, cv, seed)
    return _laid_out(instance, mean_out), _laid_out(instance, saa_out)


def _laid_out(instance: Instance, out: Any) -> Plan:
    """A solve's kits with their layouts (the shelf packer's where the oracle kept none)."""
    from ..heuristics.baselines import packed_kit

    layouts = out.layouts or [None] * len(out.kits)
    return Plan(
        tuple(
            Kit(tuple(k), lay) if lay is not None else packed_kit(instance, tuple(k), "kit")
            for k, lay in zip(out.kits, layouts, strict=True)
        )
    )


def timing_for(law: str, cv: float) -> Any:
    """The simulator's human model at ``cv`` under ``law`` (module docstring)."""
    from ..sim import TimingModel

    if law == "task":
        return TimingModel(participant_cv=0.0, task_cv=cv)
    return TimingModel(participant_cv=cv, task_cv=0.0)


def simulated(instance: Instance, plans: Mapping[str, Plan], law: str, cv: float, reps: int):
    """Each policy's simulated makespans and kit counts on seeds ``0 .. reps - 1``."""
    from ..sim import SimParams, effective_instance, replicate
    from ..sim.fixed import FixedPlanPolicy

    params = SimParams(timing=timing_for(law, cv), use_instance_supply=False)
    eff = effective_instance(instance, params)
    seeds = range(reps)
    out: dict[str, dict[str, Any]] = {}
    for name in (*FIXED, *ONLINE):
        policy: Any = name
        if name in plans:
            policy = FixedPlanPolicy(eff, params=params, plan=plans[name])
        try:
            recs = replicate(instance, policy, params, seeds=seeds)
        except KitDoesNotFit as exc:
            if name in plans:
                raise  # a fixed plan's kits are laid out up front (_laid_out)
            out[name] = {"error": one_line(exc)}
            continue
        out[name] = {
            "makespan": [float(r["makespan"]) for r in recs],
            "n_kits": [float(r["n_kits"]) for r in recs],
        }
    return out


def robust_sim_cell(cell: RobustSimCell) -> dict[str, Any]:
    """The cell's recomputed plans, their timeline estimates and the simulated runs."""
    t0 = time.process_time()
    inst = study_instance(cell.instance, cell.trays)
    mean_plan, saa_plan = study_plans(inst, cell.cv, cell.seed)
    ev = sample(inst, EVALUATION, cell.seed, cv=cell.cv, stream=EVALUATE)
    a, b = makespans(inst, mean_plan, ev), makespans(inst, saa_plan, ev)
    timeline = {"mean-plan": estimate(a), "saa-plan": estimate(b), "vss": paired(a, b)}
    plans = {"mean-plan": mean_plan, "saa-plan": saa_plan}
    opt = sample(inst, SCENARIOS, cell.seed, cv=cell.cv, stream=OPTIMISE)
    return {
        "key": cell.key(),
        "cell": asdict(cell),
        "timeline": {k: asdict(v) for k, v in timeline.items()},
        # the SAA objective of each plan on the scenarios optimised on (robust.csv's
        # ``*_in_sample``): which solve went further
        "in_sample": {k: float(makespans(inst, p, opt).mean()) for k, p in plans.items()},
        "plans": {k: [list(kit.tasks) for kit in p.kits] for k, p in plans.items()},
        "runs": {law: simulated(inst, plans, law, cell.cv, cell.reps) for law in LAWS},
        "cpu_s": time.process_time() - t0,
    }


#: The CSV's columns, in order.
COLUMNS = (
    "instance", "trays", "cv", "seed", "law", "policy", "reps", "makespan", "makespan_low",
    "makespan_high", "gain", "gain_low", "gain_high", "n_kits", "timeline_makespan",
    "timeline_vss", "timeline_vss_low", "timeline_vss_high", "committed_vss", "in_sample",
    "committed_in_sample", "reproduced", "error",
)  # fmt: skip


def _committed(cell: Mapping[str, Any], path: Path = COMMITTED) -> Mapping[str, Any] | None:
    from .fmt import read_rows

    if not path.exists():
        return None
    for r in read_rows(path):
        if (str(r["instance"]), str(r["trays"]), float(r["cv"]), int(r["seed"])) == (
            cell["instance"],
            tray_label(cell["trays"]),
            float(cell["cv"]),
            int(cell["seed"]),
        ):
            return r
    return None


def _committed_in_sample(committed: Mapping[str, Any] | None, name: str) -> float | str:
    """The committed study's in-sample SAA objective of a fixed plan ("" for the others)."""
    column = {"mean-plan": "mean_plan_in_sample", "saa-plan": "saa_in_sample"}.get(name)
    return "" if committed is None or column is None else float(committed[column])


def _reproduced(rec: Mapping[str, Any], committed: Mapping[str, Any] | None) -> bool:
    """The recomputed plans' estimates equal the committed row's (to its 0.01 s)."""
    if committed is None:
        return False
    tl = rec["timeline"]
    pairs = (("mean_plan", "mean-plan"), ("saa_plan", "saa-plan"), ("vss", "vss"))
    return all(abs(round(tl[k]["mean"], 2) - float(committed[c])) < 0.005 for c, k in pairs)


def rows_of(records: Sequence[Mapping[str, Any]], committed: Path = COMMITTED) -> list[dict]:
    """One CSV row per cell, law and policy; numbers rounded to 0.01 s."""
    out = []
    for rec in records:
        cell = rec["cell"]
        vss = rec["timeline"]["vss"]
        old = _committed(cell, committed)
        ok = _reproduced(rec, old)
        for law, runs in rec["runs"].items():
            base = runs["mean-plan"]["makespan"]
            for name, run in runs.items():
                tl = rec["timeline"].get(name)
                common = {
                    **{k: cell[k] for k in ("instance", "cv", "seed", "reps")},
                    "trays": tray_label(cell["trays"]),
                    "law": law,
                    "policy": name,
                }
                if "error" in run:  # the policy failed in this cell (module docstring)
                    out.append(
                        {k: common.get(k, run["error"] if k == "error" else "") for k in COLUMNS}
                    )
                    continue
                est, gain = estimate(run["makespan"]), paired(base, run["makespan"])
                row = {
                    **common,
                    "makespan": est.mean,
                    "makespan_low": est.low,
                    "makespan_high": est.high,
                    "gain": gain.mean,
                    "gain_low": gain.low,
                    "gain_high": gain.high,
                    "n_kits": float(np.mean(run["n_kits"])),
                    "timeline_makespan": "" if tl is None else tl["mean"],
                    "timeline_vss": vss["mean"],
                    "timeline_vss_low": vss["mean"] - vss["half"],
                    "timeline_vss_high": vss["mean"] + vss["half"],
                    "committed_vss": "" if old is None else float(old["vss"]),
                    "in_sample": rec.get("in_sample", {}).get(name, ""),
                    "committed_in_sample": _committed_in_sample(old, name),
                    "reproduced": ok,
                    "error": "",
                }
                out.append(
                    {
                        k: round(v, 2) if isinstance(v, float) and k != "cv" else v
                        for k, v in ((k, row[k]) for k in COLUMNS)
                    }
                )
    return out


def _interval(r: Mapping[str, Any], name: str) -> str:
    return f"{float(r[name]):.2f} [{float(r[f'{name}_low']):.2f}, {float(r[f'{name}_high']):.2f}]"


def _pair(r: Mapping[str, Any], a: str, b: str) -> str:
    return " / ".join("-" if r.get(k) in ("", None) else f"{float(r[k]):.2f}" for k in (a, b))


def sim_vss_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """Per cell: the timeline's VSS (committed study, and whether the recomputed plans
    reproduce it) against the simulated VSS under each law, with 95 % paired intervals."""
    cells = list(dict.fromkeys((str(r["instance"]), str(r["trays"]), str(r["cv"])) for r in rows))
    laws = list(dict.fromkeys(str(r["law"]) for r in rows))
    body = []
    for key in cells:
        mine = [r for r in rows if (str(r["instance"]), str(r["trays"]), str(r["cv"])) == key]
        saa = {str(r["law"]): r for r in mine if r["policy"] == "saa-plan"}
        first = mine[0]
        body.append(
            [
                *key,
                _interval(first, "timeline_vss"),
                "-"
                if first["committed_vss"] in ("", None)
                else f"{float(first['committed_vss']):.2f}",
                "yes" if str(first["reproduced"]) in ("True", "true") else "no",
                _pair(saa[laws[0]], "in_sample", "committed_in_sample"),
                *(_interval(saa[law], "gain") for law in laws),
                str(first["reps"]),
            ]
        )
    head = ["instance", "trays", "cv", "timeline VSS (s)", "committed (s)", "plans reproduced"]
    head += ["SAA plan in sample, recomputed / committed (s)"]
    head += [f"simulated VSS, {law} law (s)" for law in laws] + ["R"]
    return "\n".join(markdown_lines(head, body))


#: How the rendered tables name the policies.
LABELS = {
    "mean-plan": "mean-value plan",
    "saa-plan": "SAA plan",
    "cpsat-rolling": "cpsat-rolling",
    "optimized-adaptive": "optimized-adaptive",
}


def sim_detail_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """Per cell, law and policy: the simulated mean makespan (95 % interval), the paired gain
    over the mean-value plan and the kits per run."""
    body = [
        [
            str(r["instance"]),
            str(r["trays"]),
            str(r["cv"]),
            str(r["law"]),
            LABELS.get(str(r["policy"]), str(r["policy"])),
            *(
                ("failed", "-", "-")  # its error: the summary
                if _failed(r)
                else (
                    _interval(r, "makespan"),
                    "-" if r["policy"] == "mean-plan" else _interval(r, "gain"),
                    f"{float(r['n_kits']):.1f}",
                )
            ),
        ]
        for r in rows
    ]
    head = ["instance", "trays", "cv", "law", "policy", "E makespan (s)"]
    head += ["gain over the mean-value plan (s)", "kits"]
    return "\n".join(markdown_lines(head, body))


def _range(values: Sequence[float]) -> str:
    lo, hi = min(values), max(values)
    return f"{lo:.2f} s" if round(lo, 2) == round(hi, 2) else f"{lo:.2f} to {hi:.2f} s"


def sim_summary_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """The answer in sentences, computed from the CSV: does the simulated VSS agree with the
    timeline's (task law), is the SAA plan still better (participant law), and where do the
    online policies stand against the mean-value plan."""
    saa = [r for r in rows if r["policy"] == "saa-plan"]
    out = [_reproduced_sentence([r for r in saa if r["law"] == saa[0]["law"]])]
    for law in dict.fromkeys(str(r["law"]) for r in saa):
        mine = [r for r in saa if r["law"] == law]
        meets = sum(
            float(r["gain_low"]) <= float(r["timeline_vss_high"])
            and float(r["gain_high"]) >= float(r["timeline_vss_low"])
            for r in mine
        )
        above = sum(float(r["gain_low"]) > 0 for r in mine)
        out.append(
            f"Under the {law} law the simulated VSS is "
            f"{_range([float(r['gain']) for r in mine])}, its interval meets the timeline's in "
            f"{meets} of {len(mine)} cells and lies above 0 in {above}."
        )
    for name in ONLINE:
        ran = [r for r in rows if r["policy"] == name and not _failed(r)]
        above = sum(float(r["gain_low"]) > 0 for r in ran)
        below = sum(float(r["gain_high"]) < 0 for r in ran)
        if ran:
            out.append(
                f"`{name}` gains {_range([float(r['gain']) for r in ran])} over the mean-value "
                f"plan (better in {above}, worse in {below} of {len(ran)} cell x law pairs)."
            )
        failed = [r for r in rows if r["policy"] == name and _failed(r)]
        if failed:
            out.append(
                f"`{name}` failed in {len(failed)} cell x law pairs ({_where(rows, failed)}): "
                f"{str(failed[0]['error']).rstrip('.')}."
            )
    return " ".join(out)


def _where(rows: Sequence[Mapping[str, Any]], failed: Sequence[Mapping[str, Any]]) -> str:
    """Per instance, how many of its cells the ``failed`` rows are in."""

    def cells(rs: Sequence[Mapping[str, Any]], name: str) -> set[tuple[str, str]]:
        return {(str(r["trays"]), str(r["cv"])) for r in rs if r["instance"] == name}

    parts = []
    for name in dict.fromkeys(str(r["instance"]) for r in failed):
        bad, every = len(cells(failed, name)), len(cells(rows, name))
        parts.append(
            f"every cell of {name}" if bad == every else f"{bad} of {every} cells of {name}"
        )
    return ", ".join(parts)


def _failed(r: Mapping[str, Any]) -> bool:
    """The row of a policy that failed in its cell (module docstring)."""
    return bool(r.get("error"))


def _reproduced_sentence(saa: Sequence[Mapping[str, Any]]) -> str:
    """How many cells' recomputed plans reproduce the committed study, and of the others
    how many recomputed SAA plans are better, equal or worse on the scenarios both solves
    optimised (``saa``: one SAA-plan row per cell)."""
    bad = [r for r in saa if str(r["reproduced"]) not in ("True", "true")]
    diff = [float(r["in_sample"]) - float(r["committed_in_sample"]) for r in bad]
    vss = [float(r["timeline_vss"]) for r in saa]
    better, worse = sum(d < -0.005 for d in diff), sum(d > 0.005 for d in diff)
    head = (
        f"The recomputed plans reproduce the committed study in every cell ({len(saa)} of "
        f"{len(saa)}: both expected makespans and the VSS, to the CSV's 0.01 s)."
        if not bad
        else f"The recomputed plans reproduce the committed study in {len(saa) - len(bad)} of "
        f"{len(saa)} cells; in the other {len(bad)} the recomputed SAA plan is better in sample "
        f"than the committed one in {better}, equal in {len(bad) - better - worse} and worse "
        f"in {worse}."
    )
    return (
        f"{head} Recomputed, the timeline VSS is {_range(vss)}, its interval above 0 in "
        f"{sum(float(r['timeline_vss_low']) > 0 for r in saa)} cells and below 0 in "
        f"{sum(float(r['timeline_vss_high']) < 0 for r in saa)}."
    )


#: Table name -> (its CSV file, its renderer), merged into :data:`.report_sim.SIM_TABLES`.
ROBUST_SIM_TABLES = {
    "robust_sim_summary": ("robust_sim.csv", sim_summary_markdown),
    "robust_sim_vss": ("robust_sim.csv", sim_vss_markdown),
    "robust_sim_detail": ("robust_sim.csv", sim_detail_markdown),
}


def run_robust_sim(
    out_dir: str | Path = "out/repro/robust_sim",
    quick: bool = False,
    jobs: int = 1,
    seed: int = 0,
    *,
    reps: int | None = None,
    cells: Sequence[tuple[str, int | None, float]] | None = None,
    progress: bool | None = None,
    **_: Any,
) -> dict[str, Any]:
    """The study (module docstring); ``quick``: the table at cv 0.5, 5 replications. Cells are
    saved under ``out_dir/cells/`` (a rerun computes only the missing ones)."""
    t0 = time.perf_counter()
    grid = tuple(cells) if cells else (QUICK_CELLS if quick else CELLS)
    r = reps or (QUICK_REPS if quick else REPS)
    bad = [c for c in grid if c[0] not in INSTANCES or c[2] < 0]
    if bad or r < 2:
        raise UsageError(f"bad robust-sim options {bad or r}: instances from "
                         f"{', '.join(INSTANCES)}, cv >= 0, at least 2 replications")  # fmt: skip
    from .common import file_digest, run_study_cells, study_summary

    todo = [
        RobustSimCell(n, t, c, seed, r, digest=file_digest(ROOT / INSTANCES[n])) for n, t, c in grid
    ]
    out = Path(out_dir)
    ran = run_study_cells(
        todo, robust_sim_cell, out, jobs=jobs, progress=progress, desc="robust-sim cells"
    )
    rows = rows_of(ran[0])
    head = (
        f"Robust plans in the simulator{' (QUICK: a reduced run)' if quick else ''}: the "
        "timeline's VSS against the simulated VSS (s), mean [95 % paired interval].\n\n"
    )
    files = {
        "csv": write_csv(out / "robust_sim.csv", rows, exclude=(), line_end="\n"),
        "markdown": out / "robust_sim.md",
    }
    atomic.write_text(
        files["markdown"], head + sim_vss_markdown(rows) + "\n\n" + sim_detail_markdown(rows) + "\n"
    )
    return study_summary(
        out, "robust_sim", ran, rows, files, t0=t0, quick=quick, seed=seed, cells=len(todo)
    )
