"""Build the KitBench library instances/kitbench/ (docs/kitbench.md): its design in one place.

python bench/kitbench_build.py [--out instances/kitbench]

Each instance is written by ``bilevel-kit generate`` (the command is stored in the file's
``generated_by``), and gets a row in ``index.csv`` without records yet (``bench run`` +
``bench update`` fill them). Rows of instances already in the index keep their records.

The design: seven families; sizes from 12 to about 1,000 tasks, most between 25 and 250; the
variants rotate over each family, each family starting one step further, so that every
combination of trays (1 / unlimited) x tray (tight / loose) x delivery time (0 / 10 / 30 s)
occurs, the two variants of one family and size always differ in trays, and the largest sizes
have both tray settings. Tight tray: about 6 tasks' parts by area for the random families
(``--tightness tasks/6``), 160 x 120 mm for the products; loose: about 20 tasks' parts
(``--tightness tasks/20``), the paper's 300 x 200 mm for the products.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import itertools
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bilevel_kit.cli import main  # noqa: E402
from bilevel_kit.experiments.kitbench import Library, Record  # noqa: E402
from bilevel_kit.experiments.kitbench.library import INDEX  # noqa: E402
from bilevel_kit.instance import load  # noqa: E402

#: family -> (sizes, sizes with two variants); products are sized in units.
DESIGN: dict[str, tuple[tuple[int, ...], tuple[int, ...]]] = {
    "table": ((1, 2, 5, 10, 20, 42, 83), (1, 2, 5, 10, 20)),
    "mixed": ((1, 2, 5, 10, 38), (1, 2, 5)),
    "stool": ((4, 9, 17, 34, 84), (4, 9, 17)),
    "intree": ((12, 25, 50, 100, 150, 250, 500, 1000), (25, 50, 100, 250)),
    "series-parallel": ((12, 25, 50, 100, 150, 250, 500, 1000), (25, 50, 100, 250)),
    "wide": ((12, 25, 50, 100, 250, 1000), (25, 50, 100, 250)),
    "sparse": ((12, 25, 50, 100, 250, 1000), (25, 50, 100, 250)),
}
PRODUCTS = ("table", "mixed", "stool")
SHORT = {"series-parallel": "sp"}
#: (trays, tray) in rotation: consecutive variants always differ in trays.
VARIANTS = ((1, "tight"), (None, "loose"), (1, "loose"), (None, "tight"))
DELIVERY = (0, 10, 30)
TIGHT_TRAY = "160x120"
TASKS_PER_TRAY = {"tight": 6, "loose": 20}


def _tightness(tasks: int, tray: str) -> str:
    """tasks / K with 4 significant digits, so the command's text is the exact value."""
    return f"{tasks / TASKS_PER_TRAY[tray]:.4g}"


def commands() -> list[tuple[list[str], str, str]]:
    """(generate arguments, family, tray label) of every instance, in the library's order."""
    out = []
    for phase, (family, (sizes, doubled)) in enumerate(DESIGN.items()):
        count = itertools.count(phase)  # each family starts one step further in the rotation
        for size in sizes:
            for seed in (1, 2) if size in doubled else (1,):
                i = next(count)
                trays, tray = VARIANTS[i % len(VARIANTS)]
                d = DELIVERY[i % len(DELIVERY)]
                args = [family, "--size", str(size)]
                if family in PRODUCTS:
                    base = f"{family}_u{size}"
                    args += ["--d", str(d)]
                    if tray == "tight":
                        args += ["--tray", TIGHT_TRAY]
                else:
                    base = f"{SHORT.get(family, family)}_n{size}_s{seed}"
                    args += ["--seed", str(seed), "--tightness", _tightness(size, tray)]
                    args += ["--d", str(d)]
                t = "t1" if trays == 1 else "tu"
                args += ["--trays", "1" if trays == 1 else "unlimited"]
                args += ["--name", f"{base}_{t}_{tray}_d{d}"]
                out.append((args, family, tray))
    # the paper's own instance: one table, one tray, the paper's tray, d = 2 s
    paper = ["table", "--size", "1", "--d", "2", "--trays", "1", "--name", "table_u1_t1_loose_d2"]
    out.insert(0, (paper, "table", "loose"))
    return out


def build(folder: Path) -> list[Record]:
    """Write every instance file and the index (keeping the records of known instances)."""
    folder.mkdir(parents=True, exist_ok=True)
    known = {r.instance: r for r in Library(folder).read()} if (folder / INDEX).exists() else {}
    records = []
    for args, family, tray in commands():
        name = args[args.index("--name") + 1]
        path = folder / f"{name}.json"
        with contextlib.redirect_stdout(io.StringIO()):
            code = main(["generate", *args, "--out", str(path)])
        if code != 0:
            raise SystemExit(f"generate {' '.join(args)}: exit {code}")
        inst = load(path)
        records.append(
            known.get(name)
            or Record(name, family, inst.n_tasks, inst.trays, inst.delivery_time, tray)
        )
        print(f"{name}: {inst.n_tasks} tasks", flush=True)
    Library(folder).write(records)
    return records


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "instances" / "kitbench")
    build(ap.parse_args().out)
