"""Branch, bound and remember over the ideals (completed-task sets) of the precedence graph:
an exact search for one station's makespan that proves what the models' bounds cannot
(docs/formulations.md, "Branch, bound and remember"). :mod:`.space` holds the state, its
transition and its lower bound, :mod:`.search` the best-first search with memory, and
:mod:`.method` the registered method ``bbr``."""

from .method import BbrOptions, bbr

__all__ = ["BbrOptions", "bbr"]
