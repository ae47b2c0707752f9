"""One source of truth for the per-station parameters (docs/formats.md, "Stations"):
:meth:`Instance.params_of` reads them, refuses the one-station read on several stations, and
:meth:`Instance.as_one_station` turns one declared station into the S = 1 case."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import strategies
from stations_example import worked_example_doc

from bilevel_kit.heuristics.greedy_ce import GreedyCEPolicy
from bilevel_kit.instance import from_dict
from bilevel_kit.instance.model import StationParams


def test_params_of_reads_each_station_and_refuses_the_one_station_read():
    inst = from_dict(worked_example_doc())  # A: one tray; B: d = 2, o_H = 0; the file: 1, 0.5
    assert inst.params_of("A") == StationParams(1.0, 0.5, 1)
    assert inst.params_of("B") == StationParams(2.0, 0.0, None)
    with pytest.raises(ValueError, match="2 stations have parameters of their own"):
        inst.params_of()
    with pytest.raises(ValueError, match="2 stations"):  # a one-station policy: refused
        GreedyCEPolicy(inst)
    flat = from_dict(strategies.random_doc(0, 4))
    assert flat.params_of() == flat.params_of("") == flat.station_params[""]


def test_one_declared_station_becomes_the_one_station_instance():
    doc = strategies.random_doc(1, 5)
    doc["units"] = 2
    doc["trays"] = 3
    doc["stations"] = [
        {"id": "A", "delivery_time": 6.5, "kit_overhead_human": 0.0, "serves": [doc["name"]]}
    ]
    inst = from_dict(doc)
    one = inst.as_one_station()
    assert one.stations == () and inst.as_one_station().as_one_station() == one
    assert (one.delivery_time, one.kit_overhead_human, one.trays) == (6.5, 0.0, 3)
    assert one.params_of() == inst.params_of("A") == inst.params_of()
    assert [t.id for t in one.tasks] == [t.id for t in inst.tasks]
    assert set(one.precedence) == set(inst.precedence)
    several = from_dict(worked_example_doc())
    assert several.as_one_station() is several


#: Modules that may read the instance's own ``delivery_time``, ``kit_overhead_human``,
#: ``trays`` or ``tray_limit``: they record the file's fields (a solution's timeline
#: parameters, a study's or a benchmark record's metadata) and compute no time, or (the Gantt
#: chart's tray waits) read ``tray_limit`` only without ``stations``.
RECORDS = {
    "bilevel_kit/instance/model.py",
    "bilevel_kit/validate.py",
    "bilevel_kit/repro/fig6.py",
    "bilevel_kit/experiments/kitbench/verify.py",
    "bilevel_kit/plots/gantt.py",
}


def test_no_module_reads_the_instances_own_timeline_fields(root: Path):
    """Every timeline, bound and model reads them through ``Instance.params_of`` (issue 36):
    the instance's own are only the stations' defaults."""
    pattern = re.compile(
        r"\b(instance|inst)\.(delivery_time|kit_overhead_human|trays|tray_limit)\b"
    )
    found = [
        f"{path.relative_to(root)}:{n}"
        for path in sorted((root / "bilevel_kit").rglob("*.py"))
        if str(path.relative_to(root)) not in RECORDS
        for n, line in enumerate(path.read_text().splitlines(), start=1)
        if pattern.search(line)
    ]
    assert found == []
