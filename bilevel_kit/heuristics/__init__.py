"""Heuristic solvers: the paper's baselines, the shelf packer, and (later) greedy-ce."""
