"""Instance generators: determinism, family structure, tightness, the committed set."""

from __future__ import annotations

import json

import pytest

from bilevel_kit import UsageError, load
from bilevel_kit.cli import main
from bilevel_kit.generate import generate
from bilevel_kit.instance import from_dict


def test_same_seed_same_instance_different_seed_different():
    assert generate("intree", 9, seed=4) == generate("intree", 9, seed=4)
    assert generate("intree", 9, seed=4) != generate("intree", 9, seed=5)


def test_intree_every_task_but_the_root_feeds_exactly_one():
    inst = from_dict(generate("intree", 12, seed=1))
    out_degree = {t.id: 0 for t in inst.tasks}
    for a, _ in inst.precedence:
        out_degree[a] += 1
    assert out_degree["t0"] == 0
    assert all(out_degree[t] == 1 for t in out_degree if t != "t0")


def test_series_parallel_is_acyclic_and_loads():
    for seed in range(5):
        inst = from_dict(generate("series-parallel", 10, seed=seed))
        assert inst.n_tasks == 10


@pytest.mark.parametrize("tightness", [0.5, 1.0, 2.0])
def test_tightness_sets_the_tray_area(tightness):
    inst = from_dict(generate("series-parallel", 10, seed=3, tightness=tightness))
    parts = inst.kit_parts([t.id for t in inst.tasks])
    area = sum(inst.part_types[p].area * n for p, n in parts.items())
    # a 3:2 tray of area / tightness (sides rounded up to whole mm, so slightly larger)
    assert tightness * 0.99 < area / inst.tray.area <= tightness
    assert inst.tray.width / inst.tray.height == pytest.approx(1.5, rel=0.01)


def test_mixed_has_three_products_chained_across_units():
    inst = from_dict(generate("mixed", 2))
    assert {t.product for t in inst.tasks} == {"table", "stool", "chair"}
    assert inst.n_tasks == 2 * 26
    # each product's unit-2 source follows its unit-1 sinks, products stay independent
    assert ("Sa2@1", "Sa1@2") in set(inst.precedence)
    assert not any(a.startswith("S") and b.startswith("T") for a, b in inst.precedence)


def test_table_family_and_delivery_override():
    inst = from_dict(generate("table", 3, delivery_time=30))
    assert inst.units == 3 and inst.n_tasks == 36 and inst.delivery_time == 30


def test_bad_arguments():
    with pytest.raises(UsageError, match="unknown family"):
        generate("pyramid", 3)
    with pytest.raises(UsageError, match="tightness"):
        generate("intree", 3, tightness=0)


def test_cli_writes_a_loadable_instance(tmp_path, capsys):
    out = tmp_path / "g.json"
    assert (
        main(["generate", "series-parallel", "--size", "6", "--seed", "2", "--out", str(out)]) == 0
    )
    assert load(out).n_tasks == 6
    assert json.loads(out.read_text())["description"].startswith("Random series-parallel")


def test_committed_generated_set_is_reproducible(root):
    folder = root / "instances" / "generated"
    files = sorted(folder.glob("*.json"))
    assert len(files) >= 6
    for path in files:
        doc = json.loads(path.read_text())
        load(path)
        cmd = doc["description"].split("(bilevel-kit generate ")[1].rstrip(").").split()
        family, opts = cmd[0], dict(zip(cmd[1::2], cmd[2::2], strict=True))
        again = generate(
            family,
            int(opts["--size"]),
            int(opts.get("--seed", 0)),
            float(opts.get("--tightness", 0.6)),
            float(opts["--d"]) if "--d" in opts else None,
        )
        assert again == doc, path.name
