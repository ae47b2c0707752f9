"""An interrupted write leaves no hidden temporary file and no partial output."""

from __future__ import annotations

import pytest

from bilevel_kit import atomic


def test_atomic_write_interrupted_removes_its_temp(tmp_path):
    target = tmp_path / "out.json"
    with pytest.raises(KeyboardInterrupt), atomic.atomic_path(target) as tmp:
        tmp.write_text("half")
        raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []


def test_atomic_write_interrupted_keeps_the_old_file(tmp_path, monkeypatch):
    target = tmp_path / "out.txt"
    target.write_text("old")

    def interrupted(fd: int) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(atomic.os, "fsync", interrupted)
    with pytest.raises(KeyboardInterrupt):
        atomic.write_text(target, "new")
    assert [p.name for p in tmp_path.iterdir()] == ["out.txt"]
    assert target.read_text() == "old"


def test_save_figure_interrupted_leaves_no_png(tmp_path):
    from bilevel_kit import plots

    plt = pytest.importorskip("matplotlib.pyplot")
    fig, _ = plt.subplots()
    real = fig.savefig

    def interrupted(path, **kw):
        real(path, **kw)  # the temporary PNG exists now
        raise KeyboardInterrupt

    fig.savefig = interrupted
    with pytest.raises(KeyboardInterrupt):
        plots.save_figure(fig, tmp_path / "x.png")
    assert list(tmp_path.iterdir()) == []
