"""The one resumable cell runner: keyed files, skipping finished cells, pluggable executors."""

from __future__ import annotations

import json

from toycells import Square, square

from bilevel_kit.experiments import (
    DaskExecutor,
    SerialExecutor,
    make_executor,
    run_cells,
    run_cells_counted,
    write_csv,
)
from bilevel_kit.experiments.provenance import code_identity


def test_resume_computes_only_missing_cells(tmp_path):
    cells = [Square(i) for i in range(4)]
    recs, n = run_cells_counted(cells, square, cell_dir=tmp_path, progress=False)
    assert n == 4 and [r["y"] for r in recs] == [0, 1, 4, 9]
    saved = json.loads((tmp_path / "sq2.json").read_text())
    assert saved == {"x": 2, "y": 4, "code": code_identity()}  # the code, on disk only
    (tmp_path / "sq1.json").unlink()
    seen = []

    def spy(cell: Square) -> dict[str, int]:
        seen.append(cell.x)
        return square(cell)

    again, n = run_cells_counted(cells, spy, cell_dir=tmp_path, progress=False)
    assert (seen, n, again) == ([1], 1, recs)


def test_local_dask_cluster_gives_the_same_records_in_order(tmp_path):
    cells = [Square(i) for i in range(5)]
    serial = run_cells(cells, square, progress=False)
    pooled = run_cells(cells, square, cell_dir=tmp_path, jobs=2, progress=False)
    assert serial == pooled
    assert isinstance(make_executor(2, 5), DaskExecutor)
    assert isinstance(make_executor(1, 5), SerialExecutor)
    assert isinstance(make_executor(4, 1), SerialExecutor)


def test_a_custom_executor_plugs_in():
    class Reversed:
        def run(self, fn, cells):
            for i in reversed(range(len(cells))):
                yield i, fn(cells[i])

    recs = run_cells([Square(i) for i in range(3)], square, executor=Reversed(), progress=False)
    assert [r["x"] for r in recs] == [0, 1, 2]


def test_csv_writer_line_ends_and_excluded_fields(tmp_path):
    rows = [{"a": 1, "b": [1, 2], "solution": {"x": 1}}, {"a": 2, "c": "z"}]
    write_csv(tmp_path / "crlf.csv", rows)
    assert (tmp_path / "crlf.csv").read_bytes() == b'a,b,c\r\n1,"[1, 2]",\r\n2,,z\r\n'
    write_csv(tmp_path / "lf.csv", rows, exclude=(), line_end="\n")
    text = (tmp_path / "lf.csv").read_text()
    assert text.splitlines()[0] == "a,b,solution,c" and "\r" not in text
