"""Solve an MPS model with highspy in a child process (``solver="highs"`` of the MILPs).

Run as ``python -m bilevel_kit.models.milp.highs_child MODEL OUT TIME_LIMIT SEED LOG OPTIONS
START [STARTED [PROGRESS_FD]]``: ``TIME_LIMIT`` counts from ``STARTED`` (the parent's wall clock
when it started the child), so the child's start-up and reading the model are inside it. With
``PROGRESS_FD`` (an inherited pipe) the child writes ``PRIMAL DUAL`` lines there (Python float
reprs, ``inf`` when none) on every improving solution and, at most every
:data:`PROGRESS_EVERY` s, when the bounds moved (HiGHS's MIP callbacks). It reads the
model (MPS), sets the options (``OPTIONS`` a JSON object of HiGHS options,
``LOG`` 1 or 0), loads the MIP start (``START`` a JSON file of column name -> value, or an empty
string), solves with a zero relative gap and writes a JSON result to ``OUT``: ``status``,
``optimal``, ``infeasible``, ``has_solution``, ``objective``, ``bound`` and, with a solution,
``values`` (column name -> value).

Why a child process: OR-Tools and highspy each bundle their own ``libhighs.so.1`` (same
soname, different versions); whichever is loaded first wins and the other's import then fails
with an undefined symbol (:mod:`bilevel_kit._native`). The packing oracle needs OR-Tools in
the parent, so this module must never import it (nor anything that does).
"""

from __future__ import annotations

import json
import sys
import time
from typing import IO, Any

#: Default start of the time limit (wall clock): this module's import.
STARTED = time.time()
#: Seconds between two progress lines from HiGHS's interrupt callback (improvements: always).
PROGRESS_EVERY = 0.25


def solve_mps(
    path: str,
    time_limit: float,
    seed: int,
    log: bool,
    options: dict[str, Any],
    start: str,
    started: float = STARTED,
    progress: IO[str] | None = None,
) -> dict[str, Any]:
    """Solve the MPS model at ``path`` and return the result (module docstring); the time
    limit counts from ``started`` (wall clock)."""
    import highspy

    h = highspy.Highs()
    h.setOptionValue("output_flag", log)
    h.setOptionValue("mip_rel_gap", 0.0)
    h.setOptionValue("random_seed", seed)
    for key, value in options.items():
        h.setOptionValue(key, value)
    h.readModel(path)
    if start:
        _set_start(h, start)
    if progress is not None:
        _report_progress(h, progress)
    # the limit counts from the parent's call: the import and the read above are inside it
    h.setOptionValue("time_limit", max(0.01, time_limit - (time.time() - started)))
    h.run()
    st = h.getModelStatus()
    info = h.getInfo()
    S = highspy.HighsModelStatus
    res: dict[str, Any] = {
        "status": h.modelStatusToString(st),
        "optimal": st == S.kOptimal,
        "infeasible": st in (S.kInfeasible, S.kUnboundedOrInfeasible),
        "has_solution": int(info.primal_solution_status) == 2,
        "objective": info.objective_function_value,
        "bound": info.mip_dual_bound,
    }
    if res["has_solution"]:
        res["values"] = dict(
            zip(h.getLp().col_names_, list(h.getSolution().col_value), strict=True)
        )
    return res


def _report_progress(h: Any, out: IO[str]) -> None:
    """Write ``PRIMAL DUAL`` lines to ``out`` (module docstring)."""
    last: list[Any] = [0.0, None]  # time of the last line, the bounds written

    def write(primal: float, dual: float, now: float) -> None:
        if (primal, dual) != last[1]:
            out.write(f"{primal!r} {dual!r}\n")
            out.flush()
            last[:] = [now, (primal, dual)]

    def improving(event: Any) -> None:
        d = event.data_out
        write(d.objective_function_value, d.mip_dual_bound, time.monotonic())

    def interrupt(event: Any) -> None:
        now = time.monotonic()
        if now - last[0] >= PROGRESS_EVERY:
            write(event.data_out.mip_primal_bound, event.data_out.mip_dual_bound, now)

    h.cbMipImprovingSolution.subscribe(improving)
    h.cbMipInterrupt.subscribe(interrupt)


def _set_start(h: Any, start: str) -> None:
    """Give HiGHS the (partial) MIP start of the JSON file ``start``."""
    import numpy as np

    with open(start) as f:
        given = json.load(f)
    col = {name: j for j, name in enumerate(h.getLp().col_names_)}
    pairs = sorted((col[k], v) for k, v in given.items() if k in col)
    if pairs:
        h.setSolution(
            len(pairs),
            np.array([j for j, _ in pairs], dtype=np.int32),
            np.array([v for _, v in pairs], dtype=np.float64),
        )


def main(argv: list[str]) -> None:
    path, out, tl, seed, log, opts, start = argv[:7]
    started = float(argv[7]) if len(argv) > 7 else STARTED
    progress = open(int(argv[8]), "w") if len(argv) > 8 else None  # noqa: SIM115
    res = solve_mps(
        path, float(tl), int(seed), log == "1", json.loads(opts), start, started, progress
    )
    if progress is not None:
        progress.close()
    with open(out, "w") as f:
        json.dump(res, f)


if __name__ == "__main__":
    main(sys.argv[1:])
