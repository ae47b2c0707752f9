"""The exact driver's backend protocol (:mod:`.driver`, docs/formulations.md, "One driver for
cpsat and milp"): one exact model as the driver and the LNS first (:mod:`.lns_first`) see it.
It imports nothing from the driver nor from the backends, so that both the driver and the
modules the driver imports can name it (tests/core/test_imports.py)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol, TypeVar

from ...instance import Instance
from ...methods import MethodOutput, Status
from ..budget import Budget
from .nomodel import WHOLE, HandOff, NoModelSpec

if TYPE_CHECKING:
    from ...plan import Plan
    from ..common import Packer

#: A backend's incumbent (kits, or a state).
Inc = TypeVar("Inc")


class Backend(Protocol[Inc]):
    """One exact model as the driver sees it (its run's seed and options are its own);
    ``Inc`` is its incumbent (kits, or a state)."""

    instance: Instance
    budget: Budget
    packer: Packer
    extra: dict[str, Any]
    K: int  # the kit cap, set by :meth:`start`

    @property
    def spec(self) -> NoModelSpec:
        """Its no-model costs and ``extra`` keys."""
        ...

    @property
    def margin(self) -> float:
        """Seconds kept back from the time limit."""
        ...

    def finish(self, plan: Plan | None, status: Status, bound: float | None) -> MethodOutput:
        """The result (wall time and the backend's own counters added)."""
        ...

    def known_bound(self) -> float:
        """The best makespan bound known before the model (s), for every plan."""
        ...

    def start(self) -> Inc | None:
        """The incumbent (None: none), with K and the proven bound computed."""
        ...

    def shortcut(self, inc: Inc | None) -> MethodOutput | None:
        """The result when ``inc`` attains a bound known before the model, else None."""
        ...

    def cells(self) -> int:
        """The model's task x kit variables with K kits (its size)."""
        ...

    def hand_off(self, inc: Inc, limit: HandOff = WHOLE) -> Inc:
        """``inc`` or the better incumbent the LNS finds from it in the time left (within
        ``limit``)."""
        ...

    @property
    def is_makespan(self) -> bool:
        """Does the run minimise the makespan (the ideal search's objective)?"""
        ...

    def plan(self, inc: Inc) -> Plan:
        """``inc`` as a plan (layouts not needed: its makespan is what is read)."""
        ...

    def adopt(self, plan: Plan) -> Inc:
        """A better plan found outside the model (with its layouts) as the incumbent."""
        ...

    def raise_bound(self, value: float, source: str) -> None:
        """A makespan bound for every plan found after :meth:`start` (the ideal search's):
        the bound known before the model takes it when higher (:func:`..relax.raised`)."""
        ...

    def conclude(self, inc: Inc) -> MethodOutput:
        """The result of ``inc`` without a model (the bound known before the model)."""
        ...

    def solve(self, inc: Inc | None) -> MethodOutput:
        """Build the model with K kits, search from ``inc`` (cutting kits that do not fit)."""
        ...
