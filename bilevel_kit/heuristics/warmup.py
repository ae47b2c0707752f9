"""Compile greedy-ce's kernels before a method's clock starts (docs/scaling.md#first-run).

Why: numba compiles a kernel on its first call, 10-60 s after an install (then it loads it
from its on-disk cache in about a second). Charged to ``--time-limit``, that compile made the
first run after an install plan worse than later runs with the same limit: greedy-ce puts
every task left at the deadline in a kit of its own, and ``cpsat``'s warm start left greedy-ce
out. A result must not depend on the compile cache, so every method whose run may call a
kernel declares :func:`compile_kernels` as its ``prepare`` step
(:func:`bilevel_kit.methods.register`), which :func:`bilevel_kit.methods.solve` runs before
it starts the clock.

:func:`compile_kernels` runs greedy-ce once on small built-in instances chosen so that every
compiled entry is called with every argument type greedy-ce uses (the CE block in float32 and
float64, the scorer of the numpy loop, the push-apart repair, the depth-first, beam and rest
searches): tests/heuristics/test_warmup.py checks that the paper's table and the reference
cases of greedy-ce compile nothing more after it.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from . import _kernels

#: Set once this process has compiled (or loaded) every kernel.
_state: dict[str, float | None] = {}

#: The settings of the warm-up runs: the kernels' argument types depend on neither the CE's
#: sample count and iterations nor the search's caps, so the runs stay short; the small prefix
#: cap turns the search into a beam at once.
_CE = {"samples": 16, "elite": 4, "max_iter": 3, "patience": 2}
_SEARCH = {"max_prefix_sets": 8, "beam_width": 4, "max_rest_nodes": 50}


def ready() -> bool:
    """Whether a kernel call in this process costs no compile: the kernels are compiled
    (:func:`compile_kernels` ran), or numba is disabled or missing (the numpy path)."""
    return bool(_state) or _kernels.njit() is None


def _warm_instances() -> list[object]:
    """Small instances that reach every compiled entry (module docstring): a graph of ten
    tasks with branches (whose prefix sets outgrow the warm-up's cap, so the search turns
    into a beam and its rest searches run), and a crowded tray."""
    from ..instance import document, from_dict

    parts = [{"id": p, "width": w, "height": h, "pick_time": 1.0} for p, w, h in _PARTS]
    tasks = [
        {"id": f"t{i}", "parts": [{"type": _PARTS[i % 3][0], "count": 1 + i % 2}],
         "human_time": {"mean": 4.0 + 3 * (i % 4)}}
        for i in range(10)
    ]  # fmt: skip
    branches = document("warm-up-graph", parts, tasks, tray=(150.0, 120.0), precedence=_EDGES)
    crowded = document(
        "warm-up-tray",
        [
            # its diagonal is 101.2 mm: turned, it can stick out of the 100 mm tray, which
            # sends its kit to the numpy loop and its compiled scorer
            {"id": "bar", "width": 95.0, "height": 35.0, "pick_time": 1.0},
            {"id": "sq", "width": 30.0, "height": 30.0, "pick_time": 1.0},
        ],
        [
            {"id": "a", "parts": [{"type": "bar", "count": 1}], "human_time": {"mean": 9.0}},
            {"id": "b", "parts": [{"type": "sq", "count": 5}], "human_time": {"mean": 9.0}},
            {"id": "c", "parts": [{"type": "sq", "count": 4}], "human_time": {"mean": 4.0}},
        ],
        precedence=[["a", "c"]],
    )
    return [from_dict(branches), from_dict(crowded)]


#: The graph warm-up's part types (id, width, height in mm) and precedence (a few chains
#: that branch and join, as KitBench's sparse graphs do).
_PARTS = (("p", 40.0, 30.0), ("q", 25.0, 25.0), ("r", 60.0, 20.0))
_EDGES = [["t0", "t3"], ["t1", "t3"], ["t3", "t6"], ["t2", "t5"], ["t4", "t7"], ["t5", "t8"],
          ["t6", "t9"], ["t8", "t9"]]  # fmt: skip


def compile_kernels(notify: Callable[[str], None] | None = None) -> float | None:
    """Compile (or load from numba's cache) every kernel greedy-ce calls; return the seconds
    it took in this process (0.0 when already done), None when numba is disabled or missing.

    ``notify``: told before a compile that has no on-disk cache yet (the first run after an
    install) and after it, with the seconds measured, so that a command is never silent
    through it."""
    if _kernels.njit() is None:
        return None
    if _state:
        return 0.0
    from .greedy_ce import GreedyCEOptions, greedy_ce

    cold = _kernels.cache_missing()
    if cold and notify is not None:
        notify(
            "note: compiling the cross-entropy kernels (first run after an install, once; numba "
            "caches them; not charged to any time limit)"
        )
    t0 = time.perf_counter()
    for inst in _warm_instances():
        for precision in ("float32", "float64"):
            opts = GreedyCEOptions(**_CE, **_SEARCH, precision=precision)  # type: ignore[arg-type]
            greedy_ce(inst, opts, seed=0, time_limit=None)  # type: ignore[arg-type]
    seconds = time.perf_counter() - t0
    _state["seconds"] = seconds
    if cold and notify is not None:
        notify(f"note: compiled the cross-entropy kernels in {seconds:.1f} s")
    return seconds
