"""Instance generators: several units of the table, mixed products, random task graphs.

Every generator is a pure function of its arguments (a seeded ``numpy.random.Generator`` makes
every random choice) and returns an instance *document* (a dict in format ``bilevel-kit/1``),
so generated files are reproducible from the command that made them, which is recorded in
their ``description``.

Families:

* ``table``: ``size`` units of the paper's table (``instances/hrc_table.json``).
* ``mixed``: ``size`` units of a mixed-model line: the table, the stool of Fig. 2 and a
  chair-like product built from the same HRC model-set parts.
* ``intree``: a random assembly tree of ``size`` tasks (each task feeds one later task).
* ``series-parallel``: a random series-parallel graph of ``size`` tasks.
* ``wide``: ``size`` tasks in many short independent chains (1 to 4 tasks each).
* ``sparse``: a sparse random graph of ``size`` tasks over 6 part types: each task has a
  one-in-five chance of an arc to a task up to 40 positions later.
* ``stool``: ``size`` units of the stool of Fig. 2 (``instances/stool.json``).

``tightness`` sets the tray for the random families: tray area = total part area / tightness
(1.0: the whole product exactly fills the tray by area; larger values force more kits). It and
``seed`` apply to the random families only (``bilevel-kit generate`` refuses them for
``table``, ``mixed`` and ``stool``). ``tray`` replaces the family's tray (the paper's 300 x 200
mm, or the one ``tightness`` gives), ``trays`` its trays in circulation (the table: 1, the
others: unlimited) and ``name`` its name. ``stations`` S puts the family on S assembly
stations served by one robot (docs/timeline.md#several-stations): each station builds the
family's units of every product (so the instance has S times the units), station ``Sk``
serving the k-th block of units, with the instance's delivery time, trays and overheads. A
tray so small that some task's parts do not fit it on their own is an error: no method
could solve that instance.

Names (docs/formats.md#names-of-generated-instances): ``FAMILY_uU`` for the products,
``FAMILY_nN_sS`` (seed S) for the random families, then ``_dD`` when the delivery time is not the
family's own and ``_stK`` on K stations (``table_u2_d5_st3``); ``name`` replaces the whole.

:func:`command_line` is the command that makes a document; the description quotes it and
``bilevel-kit generate`` stores it as the instance's ``generated_by`` (docs/formats.md), so
every generated file says how to make it again.
"""

from __future__ import annotations

import copy
import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np

from .errors import UsageError

FAMILIES = ("table", "mixed", "stool", "intree", "series-parallel", "wide", "sparse")
#: The families built from the paper's products (sized in units, no seed or tightness).
PRODUCTS = ("table", "mixed", "stool")
#: Each random family's number in its random stream's seed (fixed: files stay reproducible).
_STREAM = {"intree": 2, "series-parallel": 3, "wide": 4, "sparse": 5}
DEFAULT_TIGHTNESS = 0.6
#: The random families' delivery time (s) when ``--d`` is not given.
DEFAULT_DELIVERY = 5.0
_ROOT = Path(__file__).resolve().parent.parent
_SD_RATIO = 61.14 / 374.78


def _product_doc(file: str = "hrc_table.json") -> dict[str, Any]:
    path = _ROOT / "instances" / file
    if path.exists():
        doc: dict[str, Any] = json.loads(path.read_text())
        return doc
    raise UsageError(f"generate: this family needs {path}")


def command_line(
    family: str,
    size: int,
    seed: int = 0,
    tightness: float | None = None,
    delivery_time: float | None = None,
    *,
    trays: int | str | None = None,
    tray: tuple[float, float] | None = None,
    name: str | None = None,
    stations: int | None = None,
) -> str:
    """The ``bilevel-kit generate`` command that makes this document (a random family always
    names its seed, tightness and delivery time; the other options only when given)."""
    words = ["bilevel-kit", "generate", family, "--size", str(size)]
    if family in PRODUCTS:
        if delivery_time is not None:
            words += ["--d", f"{delivery_time:g}"]
    else:
        t = DEFAULT_TIGHTNESS if tightness is None else tightness
        d = DEFAULT_DELIVERY if delivery_time is None else delivery_time
        if tray is None:
            words += ["--seed", str(seed), "--tightness", f"{t:g}", "--d", f"{d:g}"]
        else:
            words += ["--seed", str(seed), "--d", f"{d:g}"]
    if trays is not None:
        words += ["--trays", str(trays)]
    if tray is not None:
        words += ["--tray", f"{tray[0]:g}x{tray[1]:g}"]
    if name is not None:
        words += ["--name", name]
    if stations is not None:
        words += ["--stations", str(stations)]
    return " ".join(words)


def _units_of(
    family: str, file: str, what: str, size: int, delivery_time: float | None
) -> dict[str, Any]:
    """``size`` units of the product in ``instances/<file>``: the table and the stool differ
    only in their file and in the words describing them."""
    doc = _product_doc(file)
    doc["name"] = f"{family}_u{size}"
    doc["units"] = size
    if delivery_time is not None:
        doc["delivery_time"] = float(delivery_time)
    doc["description"] = f"{size} units of {what} (bilevel-kit generate {family} --size {size})."
    return doc


def table(size: int, delivery_time: float | None = None) -> dict[str, Any]:
    """``size`` units of the paper's table."""
    return _units_of("table", "hrc_table.json", "the paper's table", size, delivery_time)


def stool(size: int, delivery_time: float | None = None) -> dict[str, Any]:
    """``size`` units of the stool of Fig. 2."""
    what = "the stool of the paper's Fig. 2: a1 'insert screws to top' precedes a2 and a3, the legs"
    return _units_of("stool", "stool.json", what, size, delivery_time)


def _task(tid: str, name: str, product: str, parts: dict[str, int], human: float) -> dict[str, Any]:
    return {
        "id": tid,
        "name": name,
        "product": product,
        "parts": [{"type": t, "count": n} for t, n in parts.items()],
        "human_time": {"mean": human, "sd": round(human * _SD_RATIO, 3)},
    }


def mixed(size: int, delivery_time: float | None = None) -> dict[str, Any]:
    """A mixed-model line: table + stool + chair per unit, sharing the model-set part types."""
    base = _product_doc("hrc_table.json")
    part_types = copy.deepcopy(base["part_types"])
    part_types += [
        {
            "id": "seat",
            "name": "stool top",
            "width": 120.0,
            "height": 120.0,
            "pick_time": 10.0,
            "rotatable": True,
        },
        {
            "id": "stool_leg",
            "name": "stool leg",
            "width": 150.0,
            "height": 15.0,
            "pick_time": 8.0,
            "rotatable": True,
        },
    ]
    tasks = [dict(t, id=f"T{t['id']}", product="table") for t in copy.deepcopy(base["tasks"])]
    edges = [[f"T{a}", f"T{b}"] for a, b in base["precedence"]]
    # the stool of Fig. 2 (numbers as in instances/stool.json)
    tasks += [
        _task("Sa1", "stool: insert screws to top", "stool", {"seat": 1, "screw_long": 4}, 20.0),
        _task("Sa2", "stool: insert front legs", "stool", {"stool_leg": 2}, 15.0),
        _task("Sa3", "stool: insert back legs", "stool", {"stool_leg": 2}, 15.0),
    ]
    edges += [["Sa1", "Sa2"], ["Sa1", "Sa3"]]
    # a chair: four legs with feet, two back posts with connectors, then the backrest
    for i in range(1, 5):
        tasks.append(
            _task(
                f"Cfoot{i}",
                f"chair leg {i}: foot bracket",
                "chair",
                {"leg": 1, "foot": 1, "screw_short": 1},
                30.0,
            )
        )
        tasks.append(
            _task(f"Cseat{i}", f"chair leg {i}: to the seat", "chair", {"screw_long": 2}, 32.0)
        )
        edges.append([f"Cfoot{i}", f"Cseat{i}"])
    for j in range(1, 3):
        tasks.append(
            _task(
                f"Cpost{j}",
                f"chair back post {j}",
                "chair",
                {"leg": 1, "connector": 1, "screw_short": 1},
                28.0,
            )
        )
    tasks.append(_task("Cback", "chair: attach the backrest", "chair", {"screw_long": 4}, 40.0))
    edges += [[f"Cseat{i}", "Cback"] for i in range(1, 5)] + [
        ["Cpost1", "Cback"],
        ["Cpost2", "Cback"],
    ]
    doc = {
        "format": "bilevel-kit/1",
        "name": f"mixed_u{size}",
        "description": "Mixed-model line: the paper's table, the stool of Fig. 2 and a chair-like "
        f"product from the same HRC model-set parts, {size} unit(s) "
        f"(bilevel-kit generate mixed --size {size}).",
        "assumptions": [
            "Table tasks and numbers as in instances/hrc_table.json; stool as instances/stool.json "
            "(its screws are the model set's long screws); chair: 4 legs with foot brackets "
            "screwed to the seat, 2 back posts with connectors, then the backrest; human times "
            "chosen in the range of the table's.",
        ],
        "tray": base["tray"],
        "delivery_time": base["delivery_time"] if delivery_time is None else float(delivery_time),
        "kit_overhead": base["kit_overhead"],
        "part_types": part_types,
        "tasks": tasks,
        "precedence": edges,
        "units": size,
    }
    return doc


def _random_parts(rng: np.random.Generator, n_types: int) -> list[dict[str, Any]]:
    out = []
    for k in range(n_types):
        w, h = sorted(rng.integers(8, 90, size=2).tolist(), reverse=True)
        out.append(
            {
                "id": f"p{k}",
                "width": float(w),
                "height": float(h),
                "pick_time": float(rng.integers(2, 9)),
                "rotatable": bool(rng.random() < 0.8),
            }
        )
    return out


def _series_parallel(
    rng: np.random.Generator, ids: list[str]
) -> tuple[list[list[str]], list[str], list[str]]:
    """Edges, sources and sinks of a random series-parallel graph over ``ids``."""
    if len(ids) == 1:
        return [], ids[:], ids[:]
    cut = int(rng.integers(1, len(ids)))
    ea, sa, ta = _series_parallel(rng, ids[:cut])
    eb, sb, tb = _series_parallel(rng, ids[cut:])
    if rng.random() < 0.5:  # series: every sink of A precedes every source of B
        return ea + eb + [[t, s] for t in ta for s in sb], sa, tb
    return ea + eb, sa + sb, ta + tb


def _random_edges(rng: np.random.Generator, family: str, ids: list[str]) -> list[list[str]]:
    """The precedence arcs of a random family over ``ids`` (see the module docstring)."""
    n = len(ids)
    if family == "intree":
        # task j > 0 feeds a random earlier-numbered parent: the root t0 is the final assembly
        return [[ids[j], ids[int(rng.integers(0, j))]] for j in range(1, n)]
    if family == "series-parallel":
        return _series_parallel(rng, ids)[0]
    edges = []
    if family == "wide":  # consecutive runs of 1 to 4 tasks are chains
        start = 0
        while start < n:
            end = min(n, start + int(rng.integers(1, 5)))
            edges += [[ids[j], ids[j + 1]] for j in range(start, end - 1)]
            start = end
        return edges
    for j in range(n - 1):  # sparse: P = 1/5 of one arc to one of the next 40 tasks
        if rng.random() < 0.2:
            edges.append([ids[j], ids[j + int(rng.integers(1, min(40, n - 1 - j) + 1))]])
    return edges


def random_graph(
    family: str, size: int, seed: int, tightness: float = 0.6, delivery_time: float = 5.0
) -> dict[str, Any]:
    """A random product of ``size`` tasks: an in-tree, a series-parallel graph, short chains
    (``wide``) or a sparse graph (``sparse``)."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, size, _STREAM[family]]))
    types = _random_parts(rng, 6 if family == "sparse" else int(rng.integers(2, 5)))
    ids = [f"t{j}" for j in range(size)]
    edges = _random_edges(rng, family, ids)
    tasks = []
    area = 0.0
    for tid in ids:
        chosen = rng.choice(len(types), size=int(rng.integers(1, 3)), replace=False)
        parts = {types[k]["id"]: int(rng.integers(1, 3)) for k in sorted(chosen.tolist())}
        area += sum(
            types[int(k[1:])]["width"] * types[int(k[1:])]["height"] * n for k, n in parts.items()
        )
        tasks.append(_task(tid, f"task {tid}", "product", parts, float(rng.integers(10, 41))))
    side = math.sqrt(area / tightness / 1.5)  # a 3:2 tray of the requested area
    width = max(math.ceil(side * 1.5), max(t["width"] for t in types))
    height = max(math.ceil(side), max(t["height"] for t in types))
    return {
        "format": "bilevel-kit/1",
        "name": f"{family}_n{size}_s{seed}",
        "description": f"Random {family} product (bilevel-kit generate {family} --size {size} "
        f"--seed {seed} --tightness {tightness:g} --d {delivery_time:g}).",
        "assumptions": [
            "Random: part sizes 8-90 mm, pick times 2-8 s, human times 10-40 s, "
            "1-2 part types per task with 1-2 parts each, per-kit overheads 2 s "
            "(robot) and 1 s (human)."
        ],
        "tray": {"width": float(width), "height": float(height)},
        "delivery_time": float(delivery_time),
        "kit_overhead": {"robot": 2.0, "human": 1.0},
        "part_types": types,
        "tasks": tasks,
        "precedence": edges,
        "units": 1,
    }


def generate(
    family: str,
    size: int,
    seed: int = 0,
    tightness: float | None = None,
    delivery_time: float | None = None,
    *,
    trays: int | str | None = None,
    tray: tuple[float, float] | None = None,
    name: str | None = None,
    stations: int | None = None,
) -> dict[str, Any]:
    """An instance document of the given family (see the module docstring); ``seed`` and
    ``tightness`` only shape the random families, ``trays`` (an integer >= 1 or
    ``"unlimited"``), ``tray`` (width, height in mm) and ``name`` replace the family's, and
    ``stations`` puts it on that many assembly stations."""
    if family not in FAMILIES:
        raise UsageError(f"unknown family {family!r}; choose from {', '.join(FAMILIES)}")
    if size < 1:
        raise UsageError("--size must be >= 1")
    if tightness is not None and not (tightness > 0 and math.isfinite(tightness)):
        raise UsageError(f"--tightness must be a finite number > 0, got {tightness!r}")
    if tightness is not None and tray is not None:
        raise UsageError("give --tray or --tightness, not both (both set the tray)")
    check_size(family, size, stations)  # before building: a size is a promise of memory
    if family == "table":
        doc = table(size, delivery_time)
    elif family == "mixed":
        doc = mixed(size, delivery_time)
    elif family == "stool":
        doc = stool(size, delivery_time)
    else:
        t = DEFAULT_TIGHTNESS if tightness is None else tightness
        d = DEFAULT_DELIVERY if delivery_time is None else delivery_time
        doc = random_graph(family, size, seed, t, d)
    if delivery_time is not None and delivery_time != default_delivery(family):
        # two --d variants are two instances: their names differ (reports, figures, cells)
        doc["name"] = f"{doc['name']}_d{delivery_time:g}"
    _apply_options(doc, trays, tray, name)
    if stations is not None:
        _apply_stations(doc, stations)
    cmd = command_line(
        family,
        size,
        seed,
        tightness,
        delivery_time,
        trays=trays,
        tray=tray,
        name=name,
        stations=stations,
    )
    doc["description"] = re.sub(r"\(bilevel-kit generate [^)]*\)", f"({cmd})", doc["description"])
    if family not in PRODUCTS or tray is not None:
        _check_solvable(doc, tightness, tray)
    return doc


def default_delivery(family: str) -> float:
    """The delivery time (s) a family gets without ``--d``: a product's file's, else
    :data:`DEFAULT_DELIVERY`; a name shows ``_d`` only for another one (docs/formats.md)."""
    if family not in PRODUCTS:
        return DEFAULT_DELIVERY
    file = "stool.json" if family == "stool" else "hrc_table.json"  # mixed: the table's d
    return float(_product_doc(file)["delivery_time"])


def tasks_per_unit(family: str, size: int) -> int:
    """How many tasks one unit of ``family`` has (a random family: one unit of ``size``
    tasks), found without building ``size`` of anything."""
    if family == "table":
        return len(table(1)["tasks"])
    if family == "stool":
        return len(stool(1)["tasks"])
    if family == "mixed":
        return len(mixed(1)["tasks"])
    return size


def check_size(family: str, size: int, stations: int | None = None) -> None:
    """A :class:`UsageError` with the allowed range when the instance would have more than
    :data:`~bilevel_kit.instance.MAX_TASKS` tasks over all units and stations
    (docs/formats.md#ranges), decided from the numbers alone: ``--stations 1000000000``
    would otherwise build a list of a billion units before any check."""
    from .instance import MAX_TASKS

    n = 1 if stations is None else stations
    per_unit = tasks_per_unit(family, size)
    units = size if family in PRODUCTS else 1
    total = per_unit * units * n
    if total <= MAX_TASKS:
        return
    what = "units" if family in PRODUCTS else "tasks"
    size_max = MAX_TASKS // ((per_unit if family in PRODUCTS else 1) * n)
    stations_max = MAX_TASKS // (per_unit * units)
    if stations is None or stations_max < 1:
        on = "" if stations is None else f" on {n:,} station(s)"
        rng = f"--size must be in [1, {size_max:,}] {what} for {family!r}{on}"
        culprit = f"--size {size:,}"
    else:
        rng = f"--stations must be in [1, {stations_max:,}] for {family!r} --size {size:,}"
        culprit = f"--stations {n:,}"
    raise UsageError(
        f"{culprit}: {per_unit:,} task(s) x {units:,} unit(s) x {n:,} station(s) = {total:,} "
        f"tasks, above the limit of {MAX_TASKS:,} (docs/formats.md#ranges); {rng}"
    )


def _apply_options(
    doc: dict[str, Any],
    trays: int | str | None,
    tray: tuple[float, float] | None,
    name: str | None,
) -> None:
    """``trays``, ``tray`` and ``name`` written into ``doc`` (ranges checked on loading)."""
    if trays == "unlimited":
        doc.pop("trays", None)
    elif trays is not None:
        if isinstance(trays, bool) or not isinstance(trays, int) or trays < 1:
            raise UsageError(f"--trays must be an integer >= 1 or 'unlimited', got {trays!r}")
        doc["trays"] = trays
    if tray is not None:
        doc["tray"] = {"width": float(tray[0]), "height": float(tray[1])}
    if name is not None:
        if not name:
            raise UsageError("--name must not be empty")
        doc["name"] = name


def _apply_stations(doc: dict[str, Any], n: int) -> None:
    """``n`` stations, each building the document's units of every product: the units grow
    ``n``-fold and station ``Sk`` serves the k-th block of them (the module docstring)."""
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise UsageError(f"--stations must be an integer >= 1, got {n!r}")
    units = int(doc.get("units", 1))
    for t in doc["tasks"]:
        t.setdefault("product", doc["name"])  # the name changes below
    products = list(dict.fromkeys(t["product"] for t in doc["tasks"]))
    doc["units"] = units * n
    doc["stations"] = [
        {
            "id": f"S{k}",
            "serves": [
                f"{p}@{u}" for u in range((k - 1) * units + 1, k * units + 1) for p in products
            ],
        }
        for k in range(1, n + 1)
    ]
    doc["name"] = f"{doc['name']}_st{n}"
    doc["description"] = doc["description"].replace(
        " (bilevel-kit generate",
        f", on {n} assembly station(s) served by one robot (bilevel-kit generate",
    )


def _check_solvable(
    doc: dict[str, Any], tightness: float | None, tray: tuple[float, float] | None
) -> None:
    """Every task's parts fit the tray on their own, else no plan exists (a kit holds at least
    one task): the area bound first, then the packing oracle for the few that pass it. Only a
    proof refuses (docs/formulations.md#what-optimal-means): one at any angle means no method
    can solve the instance, one for 0/90-degree layouts that the exact models and the
    baselines cannot (only parts at other angles might fit); an undecided answer passes."""
    from .instance import from_dict
    from .models.packing import ANY_ANGLE
    from .models.packing_oracle import kit_verdict

    inst = from_dict(doc, "<generated>")
    tried: set[frozenset[tuple[str, int]]] = set()
    for task in inst.tasks:
        counts = dict(task.parts)
        key = frozenset(counts.items())
        if key in tried:
            continue
        tried.add(key)
        area = sum(inst.part_types[p].area * n for p, n in counts.items())
        fit = None if area > inst.tray.area else kit_verdict(inst, counts, 2.0)
        if fit is None or fit.fits is False:
            what = (
                "--tray" if tray is not None else f"--tightness {tightness or DEFAULT_TIGHTNESS:g}"
            )
            fix = "a larger --tray" if tray is not None else "a lower --tightness"
            how = (
                ", so no method can solve this instance"
                if fit is None or fit.scope == ANY_ANGLE
                else " at 0 or 90 degrees, so neither the exact models nor the baselines can "
                "solve this instance"
            )
            raise UsageError(
                f"{what}: the parts of task {task.id} do not fit the "
                f"{inst.tray.width:g} x {inst.tray.height:g} mm tray on their own{how}; "
                f"use {fix}"
            )
