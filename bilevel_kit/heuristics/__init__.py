"""Methods that plan without proving: the paper's solver and its baselines.

The paper's bilevel heuristic (Section IV): the greedy rolling-horizon upper level
(:mod:`.upper_level`, :mod:`.greedy_search`, :mod:`.greedy_ce`) and the cross-entropy lower
level (:mod:`.cross_entropy`, Algorithm 1), with its compiled kernels and the convex layout
polish (:mod:`.convex`); the paper's baselines Single Task and Whole Assembly
(:mod:`.baselines`) and the shelf packer they use (:mod:`.shelf`).

Nothing here imports :mod:`bilevel_kit.models`: the exact models may start from a heuristic
plan, never the reverse (docs/extending.md).
"""
