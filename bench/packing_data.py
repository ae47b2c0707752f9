"""Build the packing-decision benchmark set in ``bench/data/packing/`` (see its README.md).

Run from the repository root: ``python bench/packing_data.py``. Deterministic: rerunning
rewrites the same files. Three classes of stand-alone pack files (docs/formats.md):

* ``cjcm``: the 42 orthogonal-packing instances of Clautiaux, Jouglet, Carlier and Moukrim
  (``cjcm.txt``, no rotation); the name tells the answer: ``F`` feasible, ``N`` infeasible,
  ``X`` open in the paper (answered here by a long reference run, see bench_packing.py);
* ``perfect``: zero-waste packings of 25 items, made by cutting a tray into 25 pieces with
  random guillotine cuts (feasible by construction; no rotation);
* ``kits``: tray kits of the toolkit's random instances (``bilevel-kit generate intree`` /
  ``series-parallel --size 30 --tightness 4``): consecutive tasks' parts filling 80-105 % of
  the tray, rotatable as the part types say (answered by the reference run).
"""

from __future__ import annotations

import csv
import json
import random
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "bench" / "data" / "packing"


def _pack_doc(W: int, H: int, items: list[tuple[int, int, int, bool]]) -> dict[str, object]:
    return {
        "tray": {"width": float(W), "height": float(H)},
        "items": [
            {"id": f"i{k}", "width": float(w), "height": float(h), "count": n, "rotatable": r}
            for k, (w, h, n, r) in enumerate(items)
        ],
    }


def cjcm() -> list[tuple[str, dict[str, object], str]]:
    out = []
    for line in (DATA / "cjcm.txt").read_text().splitlines():
        head, body = line.split("|")
        name, W, H = head.split()
        items = []
        for spec in body.split(";"):
            w, h, n = (int(v) for v in spec.split())
            items.append((w, h, n, False))
        answer = {"F": "feasible", "N": "infeasible", "X": ""}[name[3]]
        out.append((name, _pack_doc(int(W), int(H), items), answer))
    return out


def guillotine(W: int, H: int, n: int, rng: random.Random) -> list[tuple[int, int]]:
    """Cut a W x H rectangle into n pieces: split the largest piece across its longer side at a
    random integer position (pieces at least 1 wide)."""
    pieces = [(W, H)]
    while len(pieces) < n:
        pieces.sort(key=lambda p: p[0] * p[1])
        w, h = pieces.pop()
        if max(w, h) < 2:
            pieces.append((w, h))
            break
        if (w >= h and w >= 2) or h < 2:
            c = rng.randint(1, w - 1)
            pieces += [(c, h), (w - c, h)]
        else:
            c = rng.randint(1, h - 1)
            pieces += [(w, c), (w, h - c)]
    rng.shuffle(pieces)
    return pieces


def perfect() -> list[tuple[str, dict[str, object], str]]:
    out = []
    for k, (W, H) in enumerate([(40, 15), (20, 20), (60, 30), (30, 30)] * 2):
        rng = random.Random(1000 + k)
        pieces = guillotine(W, H, 25, rng)
        out.append(
            (
                f"P{k:02d}_{W}x{H}",
                _pack_doc(W, H, [(w, h, 1, False) for w, h in pieces]),
                "feasible",
            )
        )
    return out


def kits() -> list[tuple[str, dict[str, object], str]]:
    sys.path.insert(0, str(ROOT))
    from bilevel_kit.generate import generate

    out = []
    for family, seed in [("intree", 1), ("intree", 2), ("series-parallel", 3), ("intree", 4)]:
        doc = generate(family, 30, seed=seed, tightness=4.0)
        W, H = int(doc["tray"]["width"]), int(doc["tray"]["height"])
        types = {t["id"]: t for t in doc["part_types"]}
        rng = random.Random(seed)
        made = 0
        for _ in range(400):
            if made >= 3:
                break
            start = rng.randrange(len(doc["tasks"]))
            target = rng.uniform(0.8, 1.05)
            counts: dict[str, int] = {}
            fill = 0.0
            for task in (doc["tasks"] * 2)[start:]:
                for part in task["parts"]:
                    pid, n = part["type"], part["count"]
                    counts[pid] = counts.get(pid, 0) + n
                    fill += n * types[pid]["width"] * types[pid]["height"] / (W * H)
                if fill >= target:
                    break
            if not 0.8 <= fill <= 1.05:
                continue
            items = [
                (
                    int(types[p]["width"]),
                    int(types[p]["height"]),
                    n,
                    bool(types[p]["rotatable"]),
                )
                for p, n in sorted(counts.items())
            ]
            name = f"K_{family[:2]}{seed}_{made}"
            out.append((name, _pack_doc(W, H, items), ""))
            made += 1
    return out


def main() -> int:
    rows = []
    for cls, make in (("cjcm", cjcm), ("perfect", perfect), ("kits", kits)):
        (DATA / cls).mkdir(parents=True, exist_ok=True)
        for name, doc, answer in make():
            path = DATA / cls / f"{name}.json"
            path.write_text(json.dumps(doc, indent=1) + "\n")
            rows.append((name, cls, path.relative_to(DATA).as_posix(), answer))
    with open(DATA / "index.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["name", "class", "file", "answer"])
        w.writerows(rows)
    print(f"{len(rows)} instances in {DATA}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
