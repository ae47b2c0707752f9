"""``compare`` keys saved cells by the instance file's content and groups rows by file."""

from __future__ import annotations

import csv
import json
from pathlib import Path

from bilevel_kit.cli import main
from bilevel_kit.experiments import CompareCell, add_best_bound_gap


def _run(capsys, *argv: object) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open() as fh:
        return list(csv.DictReader(fh))


def test_cell_key_follows_the_file_content_not_the_path(tmp_path, root):
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    text = (root / "instances/tiny.json").read_text()
    a.write_text(text)
    b.write_text(text)
    key_a, key_b = (
        CompareCell(str(a), "single-task").key(),
        CompareCell(str(b), "single-task").key(),
    )
    assert key_a.split("__")[1:] == key_b.split("__")[1:]  # same bytes, same digest
    before = CompareCell(str(a), "single-task").key()
    doc = json.loads(text)
    doc["delivery_time"] = doc.get("delivery_time", 0) + 7
    a.write_text(json.dumps(doc))
    assert CompareCell(str(a), "single-task").key() != before


def test_editing_the_instance_recomputes_the_cell(capsys, tmp_path, root):
    inst, cells, out = tmp_path / "inst.json", tmp_path / "cells", tmp_path / "c.csv"
    doc = json.loads((root / "instances/tiny.json").read_text())
    inst.write_text(json.dumps(doc))
    argv = ["compare", inst, "--methods", "single-task", "--cells", cells, "--csv", out]
    assert _run(capsys, *argv)[0] == 0
    first = float(_rows(out)[0]["makespan"])
    for task in doc["tasks"]:  # slower human: a longer makespan
        task["human_time"]["mean"] *= 3
    inst.write_text(json.dumps(doc))
    assert _run(capsys, *argv)[0] == 0
    second = float(_rows(out)[0]["makespan"])
    assert second > first  # not the stale saved cell
    assert len(list(cells.glob("*.json"))) == 2


def test_best_bound_is_per_file_when_files_share_a_name(capsys, tmp_path):
    paths = []
    for seed in (1, 2, 3):
        p = tmp_path / f"g{seed}.json"
        assert _run(capsys, "generate", "intree", "--size", 6, "--seed", seed, "--out", p)[0] == 0
        doc = json.loads(p.read_text())
        doc["name"] = "same"
        p.write_text(json.dumps(doc))
        paths.append(p)
    out = tmp_path / "c.csv"
    code, text, _ = _run(capsys, "compare", *paths, "--methods", "single-task", "--csv", out)
    assert code == 0
    rows = _rows(out)
    assert [r["instance_file"] for r in rows] == [str(p) for p in paths]
    for r, p in zip(rows, paths, strict=True):  # each row's best bound is its own file's
        rec = add_best_bound_gap(
            [
                {
                    "instance": "same",
                    "instance_file": str(p),
                    "bound": float(r["bound"]),
                    "makespan": 1.0,
                }
            ]
        )
        assert float(r["best_bound"]) == rec[0]["best_bound"]
    assert len({r["bound"] for r in rows}) > 1  # the files really differ
    for p in paths:  # the table shows the file
        assert p.name in text


def test_add_best_bound_gap_groups_by_file():
    recs = [
        {"instance": "x", "instance_file": "a.json", "bound": 10.0, "makespan": 10.0},
        {"instance": "x", "instance_file": "b.json", "bound": 20.0, "makespan": 20.0},
    ]
    out = add_best_bound_gap(recs)
    assert [r["best_bound"] for r in out] == [10.0, 20.0]
    assert [r["gap"] for r in out] == [0.0, 0.0]


def test_no_plan_is_not_an_invalid_plan():
    from bilevel_kit.experiments.tables import table_rows

    base = {"instance": "x", "method": "m", "makespan": None, "n_kits": None}
    header, rows = table_rows(
        [
            {**base, "status": "unknown", "valid": None},
            {**base, "status": "feasible", "valid": False, "makespan": 10.0},
            {**base, "status": "error", "valid": None},
        ]
    )
    col = header.index("valid")
    assert [r[col] for r in rows] == ["no plan", "False", "-"]
