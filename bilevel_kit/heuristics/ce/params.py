"""Parameters and result of the cross-entropy kit arrangement
(:mod:`bilevel_kit.heuristics.cross_entropy`): every knob of Algorithm 1 with the value chosen
for it, and what a call returns."""

from __future__ import annotations

from dataclasses import dataclass

from ...errors import UsageError
from ...plan import Placement


@dataclass(frozen=True)
class CEParams:
    """Parameters of Algorithm 1 (paper values: 200 samples, 30 elites, 100 iterations).

    Convergence test (de Boer et al.'s rule): the run stops when the elite threshold gamma
    (the score of the ``elite``-th best sample of an iteration) has moved by at most
    ``tol * max(1, |gamma|)`` over the last ``patience`` iterations; ``converged`` says
    whether that happened before ``max_iter``. The paper's literal Algorithm 1 is
    ``CEParams(cov_smoothing=1, mirrored=False, precision="float64")``.
    """

    #: Samples drawn per iteration.
    samples: int = 200
    #: Top samples (c in the paper) that mean and covariance are refitted to.
    elite: int = 30
    #: Iteration cap (the paper's 100).
    max_iter: int = 100
    #: Relative change of gamma that still counts as progress.
    tol: float = 1e-4
    #: Iterations over which gamma must stay within ``tol`` to count as converged.
    patience: int = 10
    #: Initial standard deviation of x and y as a fraction of the tray width and height.
    init_sd_frac: float = 0.25
    #: Initial standard deviation of the angles, degrees.
    init_sd_theta: float = 30.0
    #: Diagonal floor of Sigma (added as min_sd**2): mm for positions, degrees for angles.
    #: 0.5 beat 0.05, 0.2 and 1.0 on the 28-part table kit (median fitness over seeds).
    min_sd: float = 0.5
    #: Penalty per mm of tray overhang left after projection; None: max(W6, 1) * max tray side
    #: (the overlap penalty of a 1 mm strip across the tray).
    out_weight: float | None = None
    #: "float32" (default) or "float64" for scoring the samples.
    precision: str = "float32"
    #: Push overlapping candidates apart before giving up on them.
    repair: bool = True
    #: Initial standard deviations of a run started from a given layout, relative to the
    #: random-start ones (a small value searches near the start).
    restart_sd_scale: float = 0.1
    #: Mirrored (antithetic) sampling: half the samples are mu + L z, the other half mu - L z.
    #: Each sample is still N(mu, Sigma); it halves the normals and the Cholesky product.
    mirrored: bool = True
    #: Smoothing of the mean update, mu <- a * mu_elite + (1 - a) * mu (1: the paper's rule).
    smoothing: float = 1.0
    #: Smoothing of the covariance update, Sigma <- b * Sigma_elite + (1 - b) * Sigma
    #: (1: the paper's rule; 0.3 beat 0.2, 0.5, 0.7 and 1 on the 28-part table kit).
    cov_smoothing: float = 0.3
    #: Turn each angle of the answer to the nearest quarter turn where the layout stays valid
    #: and its fitness does not drop (:mod:`bilevel_kit.heuristics.ce.snap`).
    snap: bool = False

    def __post_init__(self) -> None:
        if self.samples < 2 or not 2 <= self.elite <= self.samples:
            raise UsageError(
                f"need samples >= elite >= 2, got samples={self.samples}, elite={self.elite}"
            )
        if self.max_iter < 1 or self.patience < 1:
            raise UsageError("max_iter and patience must be >= 1")
        if self.min_sd <= 0 or self.init_sd_frac <= 0 or self.init_sd_theta < 0:
            raise UsageError("min_sd and init_sd_frac must be > 0, init_sd_theta >= 0")
        if not (0 < self.smoothing <= 1 and 0 < self.cov_smoothing <= 1):
            raise UsageError("smoothing and cov_smoothing must lie in (0, 1]")
        if self.precision not in ("float32", "float64"):
            raise UsageError(f"precision must be 'float32' or 'float64', got {self.precision!r}")


@dataclass(frozen=True)
class Arrangement:
    """A kit layout and how it was found.

    ``z`` is the exact overlap area (mm^2) of the rotated rectangles, ``z_bbox`` the paper's
    bounding-box Z; ``fitness = -(d_same - d_diff + W6 * z)`` (bigger is better; ``-inf``
    when there is no layout). ``iterations``, ``converged`` and ``trace`` (best fitness after
    each iteration) describe the last CE run performed. ``source`` names where the layout came
    from: ``ce``, ``ce+start`` (CE from the caller's start), ``ce+packer-start``, any of these
    with ``+repair``, ``packer``, each possibly with ``+snap``, or, without a layout,
    ``area-bound``/``too-large``.
    """

    layout: tuple[Placement, ...]
    fits: bool
    d_same: float
    d_diff: float
    z: float
    z_bbox: float
    fitness: float
    iterations: int
    converged: bool
    trace: tuple[float, ...]
    source: str
