"""Methods that plan without proving: the paper's solver and its baselines.

The paper's bilevel heuristic (Section IV): the greedy rolling-horizon upper level
(:mod:`.upper_level` the score F, :mod:`.greedy_search` the exact decision over prefix sets with
its pieces in :mod:`.prefix`, :mod:`.greedy_ce` the method) and the cross-entropy lower level
(:mod:`.cross_entropy`, Algorithm 1, with its pieces in :mod:`.ce`), their compiled kernels, and
the convex layout polish (:mod:`.convex`); the paper's baselines Single Task and Whole Assembly
(:mod:`.baselines`) and the shelf packer they use (:mod:`.shelf`).

Nothing here imports :mod:`bilevel_kit.models`: the exact models may start from a heuristic
plan, never the reverse (docs/extending.md).
"""
