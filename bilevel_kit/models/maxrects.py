"""A fast "yes" of the packing oracle before CP-SAT: the maximal-rectangles packer (J. Jylänki,
"A thousand ways to pack the bin", 2010; docs/formulations.md, "CP-SAT packing").

The free space of the tray is kept as the list of its *maximal* empty rectangles. Parts are
placed one at a time: each goes to the free rectangle and orientation (0 or 90 degrees, the
latter only for a part that may rotate) that a rule scores best, and every free rectangle it
overlaps is replaced by the (up to four) maximal rectangles beside it; a free rectangle inside
another is dropped. :func:`maxrects_pack` tries the part orders of :data:`ORDERS` with the rules
of :data:`RULES`, on the tray as given and transposed, and returns the first complete layout.

Sizes are on the packing grid (integers, rounded up from the true sizes), so a layout holds for
the true parts. It is a heuristic: finding no layout proves nothing, and the oracle's CP-SAT
model decides then. Of the kits a 60 s `cpsat` run on `sparse_n50_s1_tu_loose_d0` left
undecided at CP-SAT's packing limits it lays out 46 of 60, in milliseconds, the shelf packer
(tried first) none of them (bench/data/oracle_undecided.json, tests/models/test_maxrects.py).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

#: A part on the grid: (width, height, may rotate).
Size = tuple[int, int, bool]
#: A part's lower-left corner on the grid and whether it lies rotated by 90 degrees.
Corner = tuple[int, int, bool]
#: A free rectangle: (x, y, width, height).
Free = tuple[int, int, int, int]

#: Part orders tried, each a sort key of a part's (width, height, may rotate).
ORDERS: dict[str, Callable[[Size], tuple[int, ...]]] = {
    "area": lambda s: (-s[0] * s[1],),
    "long side": lambda s: (-max(s[0], s[1]), -min(s[0], s[1])),
    "short side": lambda s: (-min(s[0], s[1]), -max(s[0], s[1])),
    "perimeter": lambda s: (-(s[0] + s[1]),),
    "width": lambda s: (-s[0], -s[1]),
    "height": lambda s: (-s[1], -s[0]),
}
#: Placement rules (Jylänki's): each scores placing a ``w x h`` part at the corner of the free
#: rectangle ``(x, y, fw, fh)``, least first: bottom-left, best short side fit, best long side
#: fit, best area fit.
RULES: dict[str, Callable[[int, int, int, int, int, int], tuple[int, int]]] = {
    "bottom-left": lambda x, y, fw, fh, w, h: (y + h, x),
    "short side": lambda x, y, fw, fh, w, h: (min(fw - w, fh - h), max(fw - w, fh - h)),
    "long side": lambda x, y, fw, fh, w, h: (max(fw - w, fh - h), min(fw - w, fh - h)),
    "area": lambda x, y, fw, fh, w, h: (fw * fh - w * h, min(fw - w, fh - h)),
}
#: Every attempt: each order with each rule, on the tray and on its transpose.
ALL_ATTEMPTS = 2 * len(ORDERS) * len(RULES)
#: The attempts' work budget (:func:`attempts`): parts squared times attempts, all of them up to
#: 30 parts.
WORK = ALL_ATTEMPTS * 30**2
#: The fewest attempts a kit gets, however many its parts.
MIN_ATTEMPTS = 4


def attempts(parts: int) -> int:
    """How many attempts a kit of ``parts`` parts gets: all 48 up to 30 parts, then fewer as an
    attempt's work grows with the square of the parts (the parts times the free rectangles),
    at least :data:`MIN_ATTEMPTS`; so a kit that does not fit costs about as much as one of 30
    parts (tens of milliseconds), whatever its size."""
    return max(MIN_ATTEMPTS, min(ALL_ATTEMPTS, WORK // max(1, parts) ** 2))


def maxrects_pack(
    sizes: Sequence[Size], width: int, height: int, max_attempts: int | None = None
) -> list[Corner] | None:
    """A layout of ``sizes`` in the ``width x height`` tray (module docstring), each part's
    lower-left corner and rotation, in the order of ``sizes``; None when none of the first
    ``max_attempts`` attempts (default :func:`attempts`) finds one (orders outermost, then
    rules, the tray then its transpose)."""
    if not sizes:
        return []
    transposed = [(h, w, rot) for w, h, rot in sizes]
    left = attempts(len(sizes)) if max_attempts is None else max_attempts
    for key in ORDERS.values():
        order = sorted(range(len(sizes)), key=lambda j: key(sizes[j]))
        for rule in RULES.values():
            for parts, (w, h), back in (
                (sizes, (width, height), False),
                (transposed, (height, width), True),
            ):
                if left <= 0:
                    return None
                left -= 1
                out = _pack(parts, w, h, order, rule)
                if out is not None:  # from the transposed tray, x and y swap back
                    return [(y, x, rot) for x, y, rot in out] if back else out
    return None


def _pack(
    sizes: Sequence[Size],
    width: int,
    height: int,
    order: Sequence[int],
    rule: Callable[[int, int, int, int, int, int], tuple[int, int]],
) -> list[Corner] | None:
    """One attempt: the parts in ``order``, each where ``rule`` scores least."""
    free: list[Free] = [(0, 0, width, height)]
    out: list[Corner] = [(0, 0, False)] * len(sizes)
    for j in order:
        w, h, may_rotate = sizes[j]
        turns = ((w, h, False), (h, w, True)) if may_rotate and w != h else ((w, h, False),)
        best: tuple[tuple[int, int], int, int, int, int, bool] | None = None
        for fx, fy, fw, fh in free:
            for ww, hh, rot in turns:
                if ww <= fw and hh <= fh:
                    score = rule(fx, fy, fw, fh, ww, hh)
                    if best is None or score < best[0]:
                        best = (score, fx, fy, ww, hh, rot)
        if best is None:
            return None
        _, x, y, ww, hh, rot = best
        out[j] = (x, y, rot)
        free = _split(free, x, y, ww, hh)
    return out


def _split(free: list[Free], x: int, y: int, w: int, h: int) -> list[Free]:
    """The maximal free rectangles after a part takes ``(x, y, w, h)``. Only the pieces cut
    from the rectangles the part overlaps can be inside another: a rectangle it leaves alone
    was inside no other before, and each piece lies inside the rectangle it was cut from."""
    kept: list[Free] = []
    pieces: set[Free] = set()
    for fx, fy, fw, fh in free:
        if x >= fx + fw or x + w <= fx or y >= fy + fh or y + h <= fy:
            kept.append((fx, fy, fw, fh))
            continue
        if x > fx:
            pieces.add((fx, fy, x - fx, fh))
        if x + w < fx + fw:
            pieces.add((x + w, fy, fx + fw - x - w, fh))
        if y > fy:
            pieces.add((fx, fy, fw, y - fy))
        if y + h < fy + fh:
            pieces.add((fx, y + h, fw, fy + fh - y - h))
    new = [
        a
        for a in pieces
        if not any(_inside(a, b) for b in kept)
        and not any(b != a and _inside(a, b) for b in pieces)
    ]
    return sorted(kept + new)


def _inside(a: Free, b: Free) -> bool:
    """Is ``a`` inside ``b``?"""
    ax, ay, aw, ah = a
    bx, by, bw, bh = b
    return bx <= ax and by <= ay and ax + aw <= bx + bw and ay + ah <= by + bh
