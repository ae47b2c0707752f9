"""The large-neighbourhood search ``lns`` (docs/formulations.md): start from the best quick
plan, free windows of consecutive kits and re-optimise them exactly with CP-SAT, report the
best proven bound of :mod:`..relax`. :mod:`.method` is the registered entry, :mod:`.window`
one window's model, :mod:`.state` what a window sees of the rest of the plan, :mod:`.start`
the start plans. Importing this package loads no OR-Tools."""

from .method import LnsOptions, lns

__all__ = ["LnsOptions", "lns"]
