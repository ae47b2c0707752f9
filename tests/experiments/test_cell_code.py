"""Cells that cannot be stale: a saved cell is reused only by the code that computed it
(docs/cluster.md#cells-and-the-code-that-made-them), and a sweep whose every cell failed says
so in one line."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from toycells import Square, square

from bilevel_kit.cli import main
from bilevel_kit.cli.common import EXIT_FAILED
from bilevel_kit.experiments import cells as cells_mod
from bilevel_kit.experiments.cells import all_failed_line, run_sweep
from bilevel_kit.experiments.provenance import code_identity, source_digest, source_files

OTHER = {"version": "0.0.9", "source_sha256": "0123456789abcdef" * 4}


def _spy(seen: list[int]):
    def fn(cell: Square) -> dict[str, int]:
        seen.append(cell.x)
        return square(cell)

    return fn


def test_a_cell_made_by_other_code_is_recomputed_and_counted(tmp_path, monkeypatch, capsys):
    cells = [Square(i) for i in range(3)]
    with monkeypatch.context() as m:  # "other code" computes and saves the cells
        m.setattr(cells_mod, "code_identity", lambda: OTHER)
        old, _ = run_sweep(cells, square, cell_dir=tmp_path, progress=False, desc="toy")
    assert json.loads((tmp_path / "sq1.json").read_text())["code"] == OTHER
    capsys.readouterr()
    seen: list[int] = []
    recs, report = run_sweep(cells, _spy(seen), cell_dir=tmp_path, progress=False, desc="toy")
    err = capsys.readouterr().err.strip().splitlines()
    assert seen == [0, 1, 2] and (report.stale, report.done, report.skipped) == (3, 3, 0)
    assert err == [
        "toy: recomputing 3 of 3 saved cells made by other code (bilevel_kit 0.0.9, source "
        f"0123456789ab; this is bilevel_kit {code_identity()['version']}, source "
        f"{code_identity()['source_sha256'][:12]})"
    ]
    assert recs == old == [{"x": i, "y": i * i} for i in range(3)]  # no code field returned
    assert json.loads((tmp_path / "sq1.json").read_text())["code"] == code_identity()
    seen.clear()  # the same code: every cell reused, nothing said
    again, report = run_sweep(cells, _spy(seen), cell_dir=tmp_path, progress=False, desc="toy")
    assert (seen, report.stale, report.skipped, again) == ([], 0, 3, recs)
    assert capsys.readouterr().err == ""


def test_a_record_without_its_code_is_recomputed(tmp_path, capsys):
    """Records saved before cells named their code (e.g. bench/results/gap_cells/) load, and
    are recomputed rather than trusted."""
    (tmp_path / "sq2.json").write_text(json.dumps({"x": 2, "y": 5}))
    seen: list[int] = []
    recs, report = run_sweep(
        [Square(1), Square(2)], _spy(seen), cell_dir=tmp_path, progress=False, desc="toy"
    )
    assert seen == [1, 2] and recs[1] == {"x": 2, "y": 4} and report.stale == 1
    err = capsys.readouterr().err
    assert "toy: recomputing 1 of 2 saved cells made by other code (code not recorded;" in err


def test_workers_running_other_code_are_named(tmp_path, capsys):
    """A record carries the code of the process that computed it: a worker with other code
    makes a record that a rerun recomputes, and the sweep says so."""

    class OtherWorkers:
        def run(self, fn, cells):
            for i, cell in enumerate(cells):
                yield i, {**fn(cell), "code": OTHER}

    _, report = run_sweep(
        [Square(1), Square(2)],
        square,
        cell_dir=tmp_path,
        executor=OtherWorkers(),
        progress=False,
        desc="toy",
    )
    assert report.foreign == 2
    err = capsys.readouterr().err
    assert "toy: 2 cells were computed by workers running other code than this client" in err
    _, report = run_sweep([Square(1), Square(2)], square, cell_dir=tmp_path, progress=False)
    assert (report.stale, report.done) == (2, 2)


def test_the_source_digest_covers_exactly_the_python_files(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub" / "__pycache__").mkdir(parents=True)
    (pkg / "a.py").write_text("A = 1\n")
    (pkg / "sub" / "b.py").write_text("B = 2\n")
    (pkg / "sub" / "__pycache__" / "b.py").write_text("cached\n")
    (pkg / "scene.html").write_text("<html>")
    assert [p.relative_to(pkg).as_posix() for p in source_files(pkg)] == ["a.py", "sub/b.py"]
    before = source_digest(pkg)
    assert source_digest(pkg) == before  # deterministic
    (pkg / "scene.html").write_text("<html></html>")
    (pkg / "sub" / "__pycache__" / "b.py").write_text("other\n")
    assert source_digest(pkg) == before  # not hashed
    (pkg / "sub" / "b.py").write_text("B = 3\n")
    assert source_digest(pkg) != before
    (pkg / "sub" / "b.py").write_text("B = 2\n")
    (pkg / "sub" / "b.py").rename(pkg / "b2.py")  # same bytes, another file
    assert source_digest(pkg) != before


def test_the_package_identity_is_computed_once():
    ident = code_identity()
    assert code_identity() is ident  # cached: once per process
    assert len(ident["source_sha256"]) == 64 and ident["source_sha256"] == source_digest()
    assert len(source_files()) > 100


def test_all_failed_line():
    failed = [{"status": "error", "error": "InstanceError: x.json: $: file\nnot found"}] * 3
    assert all_failed_line("bench", failed) == (
        "bench: all 3 cells failed (each with InstanceError: x.json: $: file not found)"
    )
    mixed = [failed[0], {"status": "error", "error": "KilledWorker: w1"}]
    assert all_failed_line("compare", mixed) == (
        "compare: all 2 cells failed (the first with InstanceError: x.json: $: file not found)"
    )
    assert all_failed_line("bench", [*failed, {"status": "feasible"}]) is None
    assert all_failed_line("bench", [{"status": "refused", "error": "too large"}]) is None
    assert all_failed_line("bench", []) is None


def test_compare_whose_every_cell_failed_says_so_in_one_line(tmp_path, root, capsys):
    paths = [tmp_path / f"table{i}.json" for i in (1, 2)]
    for p in paths:
        shutil.copy(root / "instances/hrc_table.json", p)
    code = main(
        [
            *("compare", *map(str, paths), "--methods", "bilevel-milp"),
            *("-p", "bilevel-milp:max_tasks=5", "-q", "--md", str(tmp_path / "t.md")),
        ]
    )
    assert code == EXIT_FAILED
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2, err  # the sweep's summary, and one line for the failures
    assert err[0].startswith("compare: 0 done, 0 skipped, 2 failed of 2 cells")
    assert err[1].startswith("compare: all 2 cells failed (each with ")
    assert "at most 5" in err[1]


@pytest.fixture
def small_library(tmp_path) -> Path:
    from bilevel_kit.experiments.kitbench import Library, Record
    from bilevel_kit.instance import load

    folder = tmp_path / "lib"
    folder.mkdir()
    records = []
    for name, seed in (("it5", 1), ("it6", 2)):
        argv = ["generate", "intree", "--size", "5", "--seed", str(seed), "--name", name]
        assert main([*argv, "--out", str(folder / f"{name}.json")]) == 0
        inst = load(folder / f"{name}.json")
        records.append(Record(name, "intree", inst.n_tasks, inst.trays, 0.0, "loose"))
    Library(folder).write(records)
    return folder


def test_bench_run_whose_every_cell_failed_draws_nothing(
    small_library, tmp_path, monkeypatch, capsys
):
    import csv

    from bilevel_kit.experiments.kitbench import run as run_mod

    def broken(cell):
        raise RuntimeError(f"no solver for {Path(cell.instance).name}")

    monkeypatch.setattr(run_mod, "bench_cell", broken)
    out = tmp_path / "run"
    argv = ["bench", "run", "--library", str(small_library), "--methods", "single-task"]
    assert main([*argv, "--out", str(out), "-q"]) == EXIT_FAILED
    err = capsys.readouterr().err.strip().splitlines()
    assert err[1:] == [
        "bench: all 2 cells failed (the first with RuntimeError: no solver for it5.json)"
    ]
    assert not (out / "profile.png").exists() and not (out / "gap_size.png").exists()
    with (out / "results.csv").open() as fh:  # each failed row names its cell
        rows = [(r["instance"], r["method"], r["status"]) for r in csv.DictReader(fh)]
    assert rows == [("it5", "single-task", "error"), ("it6", "single-task", "error")]
