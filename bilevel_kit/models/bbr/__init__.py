"""Branch, bound and remember over the ideals (completed-task sets) of the precedence graph:
an exact search for the makespan, on one station or several, that proves what the models'
bounds cannot (docs/formulations.md, "Branch, bound and remember"). :mod:`.space` holds one
station's state, its transition and its lower bound, :mod:`.stations` those of several
stations, :mod:`.search` the best-first search with memory, and :mod:`.method` the
registered method ``bbr``."""

from .method import BbrOptions, bbr

__all__ = ["BbrOptions", "bbr"]
