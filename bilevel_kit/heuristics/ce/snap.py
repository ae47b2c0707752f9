"""Quarter-turn snapping of a cross-entropy layout (:mod:`bilevel_kit.heuristics.cross_entropy`,
option ``snap``): CE samples angles from a continuous distribution, so a part that "lies
straight" comes out at -88.4 or 2.2 degrees. Snapping turns each such angle to the nearest
multiple of 90 degrees, one part at a time, and keeps the turn only if the layout stays
exactly valid (inside the tray, no overlap, every centre reachable) and its kit fitness
(paper Eq. 11, docs/errata.md) does not drop. A turn changes no distance between centres
unless the part must move back into the tray, so the fitness usually stays equal."""

from __future__ import annotations

import numpy as np

from .accept import Candidate, assess, exactly_valid
from .kit import Kit, clip_centre, extents64

#: Relative slack on "the fitness does not drop" (float rounding of equal layouts).
FITNESS_RTOL = 1e-9


def quarter_turn(theta: float) -> float:
    """The multiple of 90 degrees nearest to ``theta``, as an angle in (-90, 90] (a rectangle
    is the same under a half turn): 0 or 90."""
    return 90.0 if round(theta / 90.0) % 2 else 0.0


def off_quarter(theta: float) -> float:
    """Degrees between ``theta`` and its nearest quarter turn (0 to 45)."""
    d = abs(theta - quarter_turn(theta)) % 180.0
    return min(d, 180.0 - d)


def snap(kit: Kit, cand: Candidate, w6: float) -> Candidate:
    """``cand`` with as many rotatable parts as possible turned to a quarter turn: parts in
    order of their distance to it (the nearest first), each turn kept when the layout stays
    valid (:func:`.accept.assess`: inside, no overlap, reachable) and its fitness does not
    drop by more than :data:`FITNESS_RTOL`; the result passes :func:`.accept.exactly_valid`
    or ``cand`` is returned. The source gets ``+snap`` when an angle changed; an invalid
    candidate is returned unchanged."""
    if not cand.valid:
        return cand
    best = cand
    off = {int(k): off_quarter(float(cand.theta[k])) for k in kit.rot_idx}
    changed = False
    for k in sorted(off, key=lambda k: (off[k], k)):
        target = quarter_turn(float(best.theta[k]))
        if float(best.theta[k]) == target:
            continue
        theta = best.theta.copy()
        theta[k] = target
        ex, ey = extents64(kit, theta)
        x, y = best.x.copy(), best.y.copy()
        x[k : k + 1] = clip_centre(x[k : k + 1], ex[k : k + 1], kit.tray.width)
        y[k : k + 1] = clip_centre(y[k : k + 1], ey[k : k + 1], kit.tray.height)
        trial = assess(kit, x, y, theta, w6, best.source)
        floor = best.fitness - FITNESS_RTOL * max(1.0, abs(best.fitness))
        if trial.valid and trial.fitness >= floor:
            best, changed = trial, True
    if not changed or not exactly_valid(
        kit.layout(best.x, best.y, best.theta), kit.tray, kit.reach
    ):
        return cand  # the final gate of every answer (it passes whenever assess did)
    best.source = cand.source + "+snap"
    return best


def unsnapped(theta: np.ndarray, rot_idx: np.ndarray, tol: float = 1e-9) -> int:
    """How many rotatable parts lie off a quarter turn."""
    return int(sum(off_quarter(float(theta[k])) > tol for k in rot_idx))
