"""Pack files for tests: packings that are hard for CP-SAT to close."""

from __future__ import annotations

import random


def perfect_packing(seed: int, n: int = 25) -> dict:
    """A pack file of n rectangles cut from the 100 x 100 tray by guillotine cuts: a zero-waste
    (perfect) packing exists, which is hard to find for a general model."""
    rng = random.Random(seed)
    rects = [(100, 100)]
    while len(rects) < n:
        rects.sort(key=lambda r: -r[0] * r[1])
        w, h = rects.pop(0)
        if w >= h:
            c = rng.randint(w // 3, 2 * w // 3)
            rects += [(c, h), (w - c, h)]
        else:
            c = rng.randint(h // 3, 2 * h // 3)
            rects += [(w, c), (w, h - c)]
    items = [
        {"id": f"i{k}", "width": float(w), "height": float(h), "count": 1, "rotatable": True}
        for k, (w, h) in enumerate(rects)
    ]
    return {"tray": {"width": 100.0, "height": 100.0}, "items": items}
