"""Parameters of a shop-floor run (everything but the instance, the policy and the seed), their
validation, and the *effective* instance they define (docs/simulation.md).

:func:`effective_instance` applies the parameters to the instance once; the simulation runs it
and the policy plans with it, so both see the same expected times.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, replace
from typing import Any

from ..errors import InstanceError, UsageError
from ..heuristics.cross_entropy import CEParams
from ..instance import DEFAULT_REPAIR_TIME, Instance, Supply, parse_trays
from .timing import TimingModel

PICK_ORDERS = ("kit", "available-first")
ESTIMATES = ("expected", "oracle")


@dataclass(frozen=True)
class SimParams:
    """Everything about a run except the instance, the policy and the seed.

    Fields:
        units: units built in sequence (None: the instance's ``units``; the paper uses 10).
        delivery_time: overrides the instance's ``d`` (s) when not None.
        trays: overrides the instance's ``trays`` (kit trays in circulation, docs/timeline.md)
            when not None: an integer >= 1, or ``"unlimited"``. The robot starts kit k only
            once the tray of kit k - trays is back (``robot_blocked`` counts the wait); the
            user study's protocol is 1 tray (``instances/hrc_table.json`` sets it).
        mat: part type -> mean inter-arrival time (s) of its feeder; adds or replaces supply
            processes on top of the instance's own ``supply`` (if ``use_instance_supply``).
        mttf: mean time to failure (s) of the feeders: one number for every supplied type, or
            a mapping per type; None keeps the instance's value (no failures if it has none).
        repair_time: fixed repair time (s) of every feeder; None: the instance's (30 s).
        use_instance_supply: start from the instance's ``supply`` section (else from none).
        initial_stock: parts in stock at t = 0 for supplied types (one number or per type;
            default 0, the feeders start empty).
        timing: the task-time model and its calibration knobs (:class:`TimingModel`).
        horizon, weights: greedy-ce's N and W1..W7 overrides (applied to the instance).
        ce: CE parameters of the optimized policy's lower level (None: the paper's).
        signed: greedy-ce's signed terms (5)-(6) as printed.
        policy_seed: seed of the policy's own randomness (CE layouts); None: the run seed. A
            fixed value lets replications share the policy's layout cache.
        pick_order: ``"kit"`` or ``"available-first"`` (see :mod:`.shopfloor`).
        human_estimate: ``"expected"`` or ``"oracle"`` (see :mod:`.shopfloor`).
        policy_options: ``key=value`` options of the policy, validated against its options
            dataclass when the policy is built (:func:`.registry.make_policy`).
        max_time: simulated-time guard (s); a run that has not ended by then is an error.
    """

    units: int | None = None
    delivery_time: float | None = None
    trays: int | str | None = None
    mat: Mapping[str, float] = field(default_factory=dict)
    mttf: float | Mapping[str, float] | None = None
    repair_time: float | None = None
    use_instance_supply: bool = True
    initial_stock: int | Mapping[str, int] = 0
    timing: TimingModel = field(default_factory=TimingModel)
    horizon: int | None = None
    weights: Mapping[str, float] | None = None
    ce: CEParams | None = None
    signed: bool = False
    policy_seed: int | None = 0
    pick_order: str = "kit"
    human_estimate: str = "expected"
    policy_options: Mapping[str, Any] = field(default_factory=dict)
    max_time: float = 1e8

    def __post_init__(self) -> None:
        if self.pick_order not in PICK_ORDERS:
            raise UsageError(f"pick_order must be one of {PICK_ORDERS}, got {self.pick_order!r}")
        if self.human_estimate not in ESTIMATES:
            raise UsageError(
                f"human_estimate must be one of {ESTIMATES}, got {self.human_estimate!r}"
            )
        if self.trays is not None:
            try:
                parse_trays(self.trays)
            except InstanceError:
                raise UsageError(
                    f"trays must be an integer >= 1 or 'unlimited', got {self.trays!r}"
                ) from None

    def to_dict(self) -> dict[str, Any]:
        """A JSON-serialisable view (for run records)."""
        out = asdict(self)
        for k in ("mat", "policy_options"):
            out[k] = dict(getattr(self, k))
        for k in ("mttf", "initial_stock", "weights"):
            v = getattr(self, k)
            out[k] = dict(v) if isinstance(v, Mapping) else v
        return out


def _check_supply_types(instance: Instance, params: SimParams) -> None:
    for t in list(params.mat) + (list(params.mttf) if isinstance(params.mttf, Mapping) else []):
        if t not in instance.part_types:
            raise UsageError(
                f"unknown part type {t!r} in the supply options; types are "
                f"{', '.join(sorted(instance.part_types))}"
            )


def _checked(t: str, s: Supply, mttf: float | None, repair: float) -> Supply:
    """The resolved supply of type ``t``: MAT and MTTF finite > 0, repair finite >= 0."""
    for name, v in (("MAT", s.mat), ("MTTF", mttf)):
        if v is not None and not (math.isfinite(v) and v > 0):
            raise UsageError(f"part type {t!r}: {name} must be finite and > 0, got {v!r}")
    if not (math.isfinite(repair) and repair >= 0):
        raise UsageError(f"part type {t!r}: repair time must be finite and >= 0")
    return Supply(float(s.mat), mttf, float(repair))


def resolve_supply(instance: Instance, params: SimParams) -> dict[str, Supply]:
    """The supply process of every supplied part type under ``params`` (see SimParams)."""
    base = dict(instance.supply) if params.use_instance_supply else {}
    _check_supply_types(instance, params)
    for t, mat in params.mat.items():
        old = base.get(t)
        base[t] = Supply(
            float(mat),
            old.mttf if old else None,
            old.repair_time if old else DEFAULT_REPAIR_TIME,
        )
    if isinstance(params.mttf, Mapping):
        missing = sorted(set(params.mttf) - set(base))
        if missing:
            raise UsageError(f"MTTF given for part type(s) without a supply: {missing}")
    out: dict[str, Supply] = {}
    for t, s in base.items():
        mttf = s.mttf
        if isinstance(params.mttf, Mapping):
            mttf = params.mttf.get(t, mttf)
        elif params.mttf is not None:
            mttf = params.mttf
        repair = s.repair_time if params.repair_time is None else params.repair_time
        out[t] = _checked(t, s, None if mttf is None else float(mttf), repair)
    return out


def effective_instance(instance: Instance, params: SimParams) -> Instance:
    """The instance a run simulates and its policy plans with: units, ``d``, trays, weights,
    horizon, the timing model's overheads and scales, and the resolved supply applied."""
    inst = instance.with_overrides(
        delivery_time=params.delivery_time,
        trays=params.trays,
        weights=params.weights,
        horizon=params.horizon,
        units=params.units,
    )
    tm = params.timing
    changes: dict[str, Any] = {"supply": resolve_supply(inst, params)}
    if tm.kit_overhead_robot is not None:
        changes["kit_overhead_robot"] = float(tm.kit_overhead_robot)
    if tm.kit_overhead_human is not None:
        changes["kit_overhead_human"] = float(tm.kit_overhead_human)
    if tm.robot_scale != 1.0:
        changes["part_types"] = {
            k: replace(p, pick_time=p.pick_time * tm.robot_scale)
            for k, p in inst.part_types.items()
        }
    if tm.robot_scale != 1.0 or tm.human_scale != 1.0:
        changes["base_tasks"] = tuple(
            replace(
                t,
                human_mean=t.human_mean * tm.human_scale,
                human_sd=t.human_sd * tm.human_scale,
                robot_time=None if t.robot_time is None else t.robot_time * tm.robot_scale,
            )
            for t in inst.base_tasks
        )
    return replace(inst, **changes)
