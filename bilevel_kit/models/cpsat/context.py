"""What one CP-SAT run carries through its steps, and what a run ends with."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

from ...instance import Instance
from ...objectives import Objective
from ...objectives import get as get_objective
from ...plan import Placement
from ...progress import Tracker
from ..budget import Budget
from ..common import Packer
from ..packing import ANY_ANGLE
from .scaling import Scaled

#: One embedded rectangle: (part type, copy j, x var, y var, rotation: 0, 1 or the two
#: orientation literals).
Rect = tuple[str, int, Any, Any, Any]


@dataclass
class Model:
    """The CP-SAT model and the variables the loops read, hint and cut."""

    model: Any
    K: int
    x: list[dict[int, Any]]
    used: list[Any]
    arrive: list[Any]
    end: list[Any]
    C: Any
    obj_const: int = 0
    #: Robot start of each kit position, None where it is the previous arrival (no tray rule).
    start: list[Any] = field(default_factory=list)
    rects: dict[tuple[int, int], list[Rect]] = field(default_factory=dict)
    counts: dict[tuple[str, int], Any] = field(default_factory=dict)
    cut_lits: dict[tuple[str, int, int], Any] = field(default_factory=dict)
    n_cuts: int = 0
    #: Several stations only (:mod:`.station_model`): ``z[s][k]``, the running ends ``F[s][k]``,
    #: each position's human work ``H_k`` and the one-tray stations' ``G[s][k]``.
    z: list[list[Any]] = field(default_factory=list)
    last: list[list[Any]] = field(default_factory=list)
    human: list[Any] = field(default_factory=list)
    back: dict[int, list[Any]] = field(default_factory=dict)
    #: Several stations only: each task's kit ``p_i`` and order encoding ``y[i][k]`` (hinted).
    order: tuple[list[Any], list[list[Any]]] = ((), ())  # type: ignore[assignment]
    #: Several stations only: each task's parts (type, count), for the counts' hints.
    parts: list[tuple[tuple[str, int], ...]] = field(default_factory=list)


class Live(Protocol):
    """What the loops tell the live progress (:class:`.live.Live`)."""

    tracker: Tracker
    #: Are the master's bounds proofs (False after an unproven Benders cut)?
    bound_valid: bool

    def kits(self, kits: Sequence[Sequence[int]] | None, scaled: int | None) -> None: ...


#: Seconds kept back from the time limit for extraction and packing the final layouts.
MARGIN = 0.15


@dataclass
class Context:
    """Instance data, scaled times and the run's parameters, shared by the model builder and
    the embedded and Benders loops.

    ``groups``: interchangeable precedence chains as task indices (symmetry breaking);
    ``objective``: a registered objective's name (:attr:`minimised`); ``budget``: the whole
    run's time budget (the loops keep :data:`MARGIN` of it back); ``packer``: the packing
    oracle on the grid of ``pack_res`` mm.
    """

    instance: Instance
    sc: Scaled
    objective: str
    groups: list[list[list[int]]]
    packer: Packer
    budget: Budget
    pack_res: float
    #: Which plans the embedded model's tray holds (docs/formulations.md#what-optimal-means):
    #: every plan when the instance's parts all fit one tray, the 0/90-degree ones on an exact
    #: packing grid, else None (a grid that rounds sizes up proves nothing).
    embed_scope: str | None = None
    #: The live progress (None: nobody listens) and the solution callback it gives the solver.
    live: Live | None = None
    callback: Any = None  # a CpSolverSolutionCallback (OR-Tools is imported lazily)
    #: The proven makespan bound of :mod:`bilevel_kit.models.relax` (None: not computed).
    proven: Any = None

    @property
    def minimised(self) -> Objective:
        """The registry's ``objective`` (:mod:`bilevel_kit.objectives`)."""
        return get_objective(self.objective)

    @property
    def ids(self) -> list[str]:
        return [t.id for t in self.instance.tasks]

    def left(self) -> float:
        """Seconds the loops may still use (the margin kept back). In a reproducible run the
        loops stop by work, and this reaching zero is the safety net firing: recorded
        (:meth:`..budget.Budget.net_fired`)."""
        out = self.budget.remaining(MARGIN)
        if out <= 0.01 and self.budget.deterministic:
            self.budget.net_fired()
        return out


@dataclass
class State:
    """What a run ends with: the best kits (objective ``obj``), the lower bound ``lower``
    (scaled objective units) proven for 0/90-degree plans, ``lower_any`` proven for every plan,
    whether ``obj`` is proven optimal (``infeasible``: no plan) among the plans of ``scope``
    (docs/formulations.md#what-optimal-means: every plan, 0/90-degree plans, or None: no
    proof)."""

    kits: list[list[int]] | None
    obj: int | None
    lower: int | None = None
    proven: bool = False
    infeasible: bool = False
    lower_any: int | None = None
    scope: str | None = ANY_ANGLE
    layouts: list[tuple[Placement, ...]] | None = None
    status_name: str = "UNKNOWN"
    info: dict[str, Any] = field(default_factory=dict)
