"""Kit arrangement by the cross-entropy method (paper Section IV-B, Algorithm 1).

The decision vector holds, for the n parts of a kit, the centres x (n), y (n) and the angles
theta (degrees) of the r rotatable parts; fixed parts keep theta = 0 and are not sampled.
Each iteration draws ``samples`` vectors from N(mu, Sigma) (Cholesky factor times standard
normals), scores them all in one numpy pass (:class:`bilevel_kit.fitness.PairScorer`),
and refits mu and the full Sigma to the ``elite`` best ones. The score to minimise is Eq. 11
with the erratum's sign (docs/errata.md), ``D_same - D_diff + W6 * Z_box``, plus a
penalty on tray overhang (below); ``trace`` and fitness values are its negation.

Choices the paper leaves open (details in :class:`CEParams`):

- Initialisation: mu uniform over the tray (angles uniform in [0, 180)), Sigma diagonal with
  standard deviations ``init_sd_frac`` times the tray side and ``init_sd_theta`` degrees.
- Tray containment by *projection*: every sampled centre is clipped so that its rotated
  bounding box lies inside the tray, and the clipped vector is what is scored and refitted
  (so the mean stays inside). Only when a rotated box is wider than the tray does clipping
  fail; that overhang is penalised with ``out_weight`` per mm.
- Sigma gets ``min_sd**2`` added on its diagonal after each refit: 30 elites cannot span the
  3n-dimensional space, so the sample covariance is singular; the floor keeps the Cholesky
  factor defined and keeps some exploration in every coordinate.
- Smoothing: Sigma <- 0.3 Sigma_elite + 0.7 Sigma by default (de Boer et al.'s tutorial,
  which the paper cites, recommends smoothed updates). With the literal refit
  (``cov_smoothing=1``) the 84-dimensional search of the 28-part table kit collapses early
  while parts still overlap: over 16 seeds the median fitness fell from 35.7k to 30.8k and 4
  runs needed the packer fallback (none with smoothing).
- Sampling is mirrored (mu + L z and mu - L z), which halves the random numbers drawn.
- Elitism: the best sample ever drawn is kept; at the end it and the final mean (and the best
  sample whose boxes did not overlap) compete on exact fitness.
- Precision: samples are scored in float32 by default (ranking only, about 4x faster than
  float64 here); every returned number is recomputed in float64 on the exact rectangles.

Quarter turns (``snap``, off by default): the answer's angles are turned to the nearest multiple
of 90 degrees, part by part, where the layout stays exactly valid and its fitness does not
drop (:mod:`bilevel_kit.heuristics.ce.snap`); CE's continuous angles otherwise leave parts
at e.g. -88.4 or 2.2 degrees.

Exactness of the answer: a candidate is accepted only if :mod:`bilevel_kit.geometry` finds
every part inside the tray and no pair penetrating by more than ``geometry.TOL``. A candidate
with small overlaps is first *repaired* by pushing overlapping bounding boxes apart; if no CE
candidate is valid, CE is re-run from the shelf packer's layout, and the packer's layout
itself competes too. Overlapping layouts are never reported as ``fits=True``.

Performance: with numba installed the iterations run compiled
(:mod:`bilevel_kit.heuristics._kernels`: sampling, extents, projection, the fused pair loop of
the scores, elite refit and Cholesky factor in one call per pool of standard normals, which
are still drawn in Python, so the random stream is the numpy loop's). Scores then differ from the
numpy loop only by float32 rounding (summation order, ``cos``/``sin`` in the last bit), which
can reorder near-tied samples; ``BILEVEL_KIT_NO_NUMBA=1`` forces the numpy loop. Runs with a
reach map or with parts that can stick out of the tray use the numpy loop (with the compiled
scorer). In the numpy loop all (n, S)- and (P, S)-sized arrays are allocated once per run;
matrix products inside the loop are cut into blocks that OpenBLAS runs single-threaded
(threaded products of this size were 10-100x slower on a busy 2-core machine).

This module is the public face (:class:`CEParams`, :class:`Arrangement`, :func:`arrange`, the
fallback chain); the pieces live in :mod:`bilevel_kit.heuristics.ce`: the parameters and
result (``params``), the kit as arrays (``kit``), batch scoring (``scoring``), one CE run
(``sampling``) and exact acceptance with the repair (``accept``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from .. import geometry
from ..fitness import layout_terms
from ..instance import Instance, PartType, Tray
from ..plan import Placement
from .ce.accept import Candidate, candidate, choose
from .ce.accept import exactly_valid as _exactly_valid  # noqa: F401 - tests import it from here
from .ce.kit import MAX_CE_PARTS, Kit, build_kit, start_vector
from .ce.params import Arrangement, CEParams
from .ce.sampling import Run, ce_run
from .ce.snap import snap

__all__ = ["Arrangement", "CEParams", "arrange"]


def arrange(
    instance: Instance,
    parts: Mapping[str, int],
    *,
    rng: np.random.Generator | int | None = 0,
    params: CEParams = CEParams(),  # noqa: B008 - frozen, so one shared default is safe
    w6: float | None = None,
    start: Sequence[Placement] | None = None,
) -> Arrangement:
    """Arrange the multiset ``parts`` (type -> count) on the instance's tray (Algorithm 1).

    Part ids are ``f"{type}-{k}"``, types in sorted order, k = 1..count. ``w6`` defaults to
    the instance's W6. ``start`` replaces the random initial mean by a given layout (searched
    with ``restart_sd_scale`` times the initial spread). Every random draw comes from
    ``np.random.default_rng(rng)``, so equal seeds give equal layouts.
    """
    gen = np.random.default_rng(rng)
    w6 = float(instance.weights["W6"] if w6 is None else w6)
    dtype = np.float32 if params.precision == "float32" else np.float64
    kit = build_kit(instance, parts, dtype)
    if kit.n == 0:
        return Arrangement((), True, 0.0, 0.0, 0.0, 0.0, 0.0, 0, True, (), "ce")
    refused = _refusal(kit)
    if refused is not None:
        return Arrangement((), False, 0.0, 0.0, 0.0, 0.0, -math.inf, 0, False, (), refused)

    if kit.n > MAX_CE_PARTS:
        return _packer_only(kit, w6)
    w_out = params.out_weight
    if w_out is None:
        w_out = max(w6, 1.0) * max(kit.tray.width, kit.tray.height)
    sd0, restart_sd = _spreads(kit, params)
    if start is None:
        mu0 = _random_mean(kit, gen)
        tag = "ce"
        run = ce_run(kit, gen, params, w6, w_out, mu0, sd0)
    else:
        mu0 = start_vector(kit, start)
        tag = "ce+start"
        run = ce_run(kit, gen, params, w6, w_out, mu0, restart_sd)
    cands = _run_candidates(kit, run, w6, tag, params.repair)
    if start is not None:
        cands.append(candidate(kit, mu0, w6, tag, params.repair))
    choice = choose(kit, cands)
    if not choice.valid:
        choice, run = _from_packer(kit, gen, params, (w6, w_out), restart_sd, choice, run)
    if params.snap:
        choice = snap(kit, choice, w6)
    return _arrangement(kit, choice, run, w6)


def _packer_only(kit: Kit, w6: float) -> Arrangement:
    """The shelf packer's layout of a kit too large for CE, or a refusal when it has none."""
    from .shelf import shelf_pack

    packed = shelf_pack(kit.tray, list(zip(kit.ids, kit.types, strict=True)))
    if packed is None:
        return Arrangement((), False, 0.0, 0.0, 0.0, 0.0, -math.inf, 0, False, (), "too-many")
    v = start_vector(kit, packed)
    choice = candidate(kit, v, w6, "packer", repair=False)
    return _arrangement(kit, choice, Run(v, None, v, [], 0, True), w6)


def _too_large(pt: PartType, tray: Tray) -> bool:
    """True when no placement can hold the part (sound, not complete, for rotatable parts:
    a rectangle's width in every direction is at least its shorter side)."""
    tol = geometry.TOL
    if not pt.rotatable:
        return pt.width > tray.width + tol or pt.height > tray.height + tol
    return min(pt.width, pt.height) > min(tray.width, tray.height) + tol


def _refusal(kit: Kit) -> str | None:
    """Why the kit has no layout, by cheap sound tests (``area-bound``: more part area than
    tray; ``too-large``: a part fits in no placement), or None."""
    if not geometry.area_fits(sum(t.area for t in kit.types), kit.tray.width, kit.tray.height):
        return "area-bound"  # the one tolerance rule (docs/timeline.md#packing-tolerance)
    if any(_too_large(t, kit.tray) for t in kit.types):
        return "too-large"
    return None


def _spreads(kit: Kit, p: CEParams) -> tuple[np.ndarray, np.ndarray]:
    """Initial standard deviations of a random start and of a run from a given layout (the
    caller's, the shelf packer's), which begins with a narrower spread."""
    tray = kit.tray
    sd0 = np.concatenate(
        [
            np.full(kit.n, p.init_sd_frac * tray.width),
            np.full(kit.n, p.init_sd_frac * tray.height),
            np.full(kit.rot_idx.size, p.init_sd_theta),
        ]
    )
    sd0 = np.maximum(sd0, p.min_sd)
    return sd0, np.maximum(sd0 * p.restart_sd_scale, p.min_sd)


def _random_mean(kit: Kit, gen: np.random.Generator) -> np.ndarray:
    """The random initial mean: centres uniform over the tray, angles uniform in [0, 180)."""
    return np.concatenate(
        [
            gen.uniform(0.0, kit.tray.width, kit.n),
            gen.uniform(0.0, kit.tray.height, kit.n),
            gen.uniform(0.0, 180.0, kit.rot_idx.size),
        ]
    )


def _run_candidates(kit: Kit, run: Run, w6: float, tag: str, repair: bool) -> list[Candidate]:
    """The run's best sample, its final mean and its best overlap-free sample, assessed."""
    vecs = [run.best, run.mean]
    if run.best_feasible is not None:
        vecs.append(run.best_feasible)
    return [candidate(kit, v, w6, tag, repair) for v in vecs]


def _from_packer(
    kit: Kit,
    gen: np.random.Generator,
    p: CEParams,
    weights: tuple[float, float],
    sd: np.ndarray,
    fallback: Candidate,
    run: Run,
) -> tuple[Candidate, Run]:
    """The fallback when no CE candidate is valid: CE re-run from the shelf packer's layout;
    its candidates, the packer's layout itself and ``fallback`` compete. (``fallback``,
    ``run``) unchanged when the packer finds nothing."""
    from .shelf import shelf_pack

    packed = shelf_pack(kit.tray, list(zip(kit.ids, kit.types, strict=True)))
    if packed is None:
        return fallback, run
    w6, w_out = weights
    p0 = start_vector(kit, packed)
    run = ce_run(kit, gen, p, w6, w_out, p0, sd)
    more = _run_candidates(kit, run, w6, "ce+packer-start", p.repair)
    more.append(candidate(kit, p0, w6, "packer", repair=False))
    return choose(kit, [*more, fallback]), run


def _arrangement(kit: Kit, choice: Candidate, run: Run, w6: float) -> Arrangement:
    """The answer: the chosen layout's exact terms, the last run's history."""
    layout = kit.layout(choice.x, choice.y, choice.theta)
    d_same, d_diff, z_bbox, z_exact = layout_terms(layout)
    return Arrangement(
        layout=layout,
        fits=choice.valid,
        d_same=d_same,
        d_diff=d_diff,
        z=z_exact,
        z_bbox=z_bbox,
        fitness=-(d_same - d_diff + w6 * z_exact),
        iterations=run.iterations,
        converged=run.converged,
        trace=tuple(run.trace),
        source=choice.source,
    )
