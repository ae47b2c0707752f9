"""The options of greedy-ce (:mod:`.greedy_ce`): the flat command-line dataclass every
``-p KEY=VALUE`` is validated against, and the policy's parameters it becomes. A module of
their own so that the policy's module stays readable (docs/extending.md#adding-a-method)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Literal

from ..errors import UsageError
from ..options import finger_room_field, option
from .ce.params import CEParams
from .greedy_search import SearchLimits


@dataclass(frozen=True)
class GreedyParams:
    """Options of ``greedy-ce``; ``None`` means "the instance's value"."""

    horizon: int | None = None
    weights: Mapping[str, float] | None = None
    signed: bool = False
    precedence: str = "hard"  # "hard" | "penalty"
    #: "exact": the search over prefix sets (:mod:`.greedy_search`); "enumerate": every
    #: sequence (the penalty form always enumerates).
    decision: str = "exact"
    max_prefix_sets: int = SearchLimits.max_prefix_sets
    beam_width: int = SearchLimits.beam_width
    max_rest_nodes: int = SearchLimits.max_rest_nodes
    ce: CEParams = field(default_factory=CEParams)
    #: Polish every CE layout with the convex-concave SOCP of models/convex_layout.py.
    polish: bool = False


_WEIGHT_NAMES = ("W1", "W2", "W3", "W4", "W5", "W6", "W7")


@dataclass(frozen=True)
class GreedyCEOptions:
    """The options of ``greedy-ce`` as the command line gives them (flat); ``None`` means the
    instance's value. The CE fields mirror :class:`CEParams` (same names and defaults)."""

    horizon: int | None = option(None, "rolling horizon N, tasks per window", min=1)
    signed: bool = option(False, "terms (5)-(6) signed as printed, not absolute")
    precedence: Literal["hard", "penalty"] = option(
        "hard", "hard: only feasible sequences; penalty: all, W1 per violation (Eq. 3)"
    )
    decision: Literal["exact", "enumerate"] = option(
        "exact", "hard precedence: exact search over prefix sets, or enumerate every sequence"
    )
    max_prefix_sets: int = option(
        SearchLimits.max_prefix_sets,
        "prefix sets per epoch beyond which the search is a beam",
        min=1,
    )
    beam_width: int = option(
        SearchLimits.beam_width, "prefix sets kept per size once the search is a beam", min=1
    )
    max_rest_nodes: int = option(
        SearchLimits.max_rest_nodes,
        "search nodes per window-rest search (then the best so far)",
        min=1,
    )
    polish: bool = option(False, "polish every CE layout with the convex SOCP")
    W1: float | None = option(
        None, "weight of term (3), per task whose predecessors are not kitted"
    )
    W2: float | None = option(None, "weight of term (4), reward per task in the kit")
    W3: float | None = option(None, "weight of term (5), |d + R(kit) - H_rem|, per s")
    W4: float | None = option(None, "weight of term (6), |d + R(rest) - H(kit)|, per s")
    W5: float | None = option(None, "weight of term (7), reward per mm of kit fitness")
    W6: float | None = option(
        None, "weight of the overlap area Z (mm^2) in the kit fitness (Eq. 11)"
    )
    W7: float | None = option(None, "weight of the W7 term (Sec. V-B), per part not yet available")
    # one CE iteration scores every sample: 10^6 took 30 s and 0.5 GB
    samples: int = option(200, "CE samples per iteration (2 to 20,000)", min=2, max=20_000)
    elite: int = option(
        30, "CE elite samples the mean and covariance are refitted to (<= samples)", min=2
    )
    # a cap of 10^12 allocated its 8 TB trace before any iteration
    max_iter: int = option(100, "CE iteration cap (1 to 1,000,000)", min=1, max=1_000_000)
    tol: float = option(
        1e-4, "CE convergence: relative change of the elite threshold (unitless, >= 0)", min=0.0
    )
    patience: int = option(
        10, "CE convergence: iterations within tol (1 to 1,000,000)", min=1, max=1_000_000
    )
    init_sd_frac: float = option(0.25, "CE initial sd of x, y as a fraction of the tray side (> 0)")
    init_sd_theta: float = option(30.0, "CE initial sd of the angles, degrees", min=0.0)
    min_sd: float = option(0.5, "CE floor of the sd (> 0): mm for positions, degrees for angles")
    out_weight: float | None = option(
        None, "CE penalty per mm of tray overhang (>= 0; none: automatic)", min=0.0
    )
    precision: Literal["float32", "float64"] = option(
        "float32", "CE precision of sample scoring (results are float64)"
    )
    repair: bool = option(True, "push overlapping CE candidates apart before rejecting them")
    restart_sd_scale: float = option(
        0.1, "CE sd of a run from a given layout, relative to a random start (>= 0)", min=0.0
    )
    mirrored: bool = option(True, "CE mirrored (antithetic) sampling: mu + L z and mu - L z")
    smoothing: float = option(1.0, "CE mean update smoothing, in (0, 1]", max=1.0)
    cov_smoothing: float = option(0.3, "CE covariance update smoothing, in (0, 1]", max=1.0)
    snap: bool = option(
        False,
        "turn each CE angle to the nearest quarter turn where the layout stays "
        "valid and its fitness does not drop",
    )
    finger_room: bool = finger_room_field()

    def __post_init__(self) -> None:
        try:
            self.ce_params()
        except UsageError as exc:  # parse_options names the method and turns this into one
            raise ValueError(str(exc)) from None

    def ce_params(self) -> CEParams:
        """The cross-entropy fields as :class:`CEParams`."""
        return CEParams(**{f.name: getattr(self, f.name) for f in fields(CEParams)})

    def to_params(self) -> GreedyParams:
        """The same options as the policy's :class:`GreedyParams`."""
        weights = {w: getattr(self, w) for w in _WEIGHT_NAMES if getattr(self, w) is not None}
        return GreedyParams(
            horizon=self.horizon,
            weights=weights or None,
            signed=self.signed,
            precedence=self.precedence,
            decision=self.decision,
            max_prefix_sets=self.max_prefix_sets,
            beam_width=self.beam_width,
            max_rest_nodes=self.max_rest_nodes,
            ce=self.ce_params(),
            polish=self.polish,
        )


#: Every option at its default.
DEFAULT_OPTIONS = GreedyCEOptions()
