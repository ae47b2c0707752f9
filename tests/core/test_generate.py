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


#: Committed generated files named before a random family's ``--d`` got its ``_dD`` token:
#: (today's name, the file's), the rest of the document identical (docs/formats.md, "Names of
#: generated instances").
BEFORE_D_TOKEN = {
    "intree_n10_s1_tight.json": ("intree_n10_s1_d20", "intree_n10_s1"),
    "sp_n10_s2_tight.json": ("series-parallel_n10_s2_d15", "series-parallel_n10_s2"),
}


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
        if path.name in BEFORE_D_TOKEN:  # committed before d had a token (docs/formats.md)
            assert (again["name"], doc["name"]) == BEFORE_D_TOKEN[path.name]
            again["name"] = doc["name"]
        assert again == doc, path.name


def test_wide_is_short_independent_chains():
    inst = from_dict(generate("wide", 60, seed=3))
    succ = {a: b for a, b in inst.precedence}
    assert len(succ) == len(inst.precedence)  # every task feeds at most one
    preds = [b for _, b in inst.precedence]
    assert len(preds) == len(set(preds))  # and is fed by at most one: chains
    heads = [t.id for t in inst.tasks if t.id not in set(preds)]
    lengths = []
    for head in heads:
        n, t = 1, head
        while t in succ:
            n, t = n + 1, succ[t]
        lengths.append(n)
    assert sum(lengths) == 60 and max(lengths) <= 4 and len(heads) >= 15


def test_sparse_arcs_reach_at_most_40_ahead_over_six_part_types():
    doc = generate("sparse", 400, seed=1)
    assert len(doc["part_types"]) == 6
    gaps = [int(b[1:]) - int(a[1:]) for a, b in doc["precedence"]]
    assert all(1 <= g <= 40 for g in gaps)
    assert 0.12 * 400 < len(gaps) < 0.28 * 400  # one in five tasks has an arc
    assert len({a for a, _ in doc["precedence"]}) == len(gaps)  # at most one arc each


def test_stool_units():
    inst = from_dict(generate("stool", 4, delivery_time=10))
    assert inst.n_tasks == 12 and inst.delivery_time == 10 and inst.trays is None


def test_trays_tray_and_name_options():
    doc = generate("table", 2, trays="unlimited", tray=(160.0, 120.0), name="t2")
    inst = from_dict(doc)
    assert inst.trays is None and (inst.tray.width, inst.tray.height) == (160, 120)
    assert inst.name == "t2"
    assert "--trays unlimited --tray 160x120 --name t2" in doc["description"]
    assert from_dict(generate("intree", 10, seed=1, trays=1)).trays == 1
    with pytest.raises(UsageError, match="not both"):
        generate("intree", 10, tightness=2, tray=(100.0, 100.0))
    with pytest.raises(UsageError, match="a larger --tray"):
        generate("table", 1, tray=(160.0, 50.0))  # a leg and a foot bracket do not fit


def test_cli_stores_the_command_and_it_makes_the_same_file(tmp_path):
    import shlex

    out = tmp_path / "a.json"
    args = ["sparse", "--size", "30", "--seed", "4", "--tightness", "3", "--trays", "1"]
    assert main(["generate", *args, "--name", "s30", "--out", str(out)]) == 0
    doc = json.loads(out.read_text())
    cmd = doc["generated_by"]
    assert cmd == (
        "bilevel-kit generate sparse --size 30 --seed 4 --tightness 3 --d 5 --trays 1 --name s30"
    )
    assert list(doc)[:4] == ["format", "name", "description", "generated_by"]
    assert load(out).generated_by == cmd and load(out).to_dict()["generated_by"] == cmd
    again = tmp_path / "b.json"
    assert main([*shlex.split(cmd)[1:], "--out", str(again)]) == 0
    assert again.read_bytes() == out.read_bytes()


def test_cli_refuses_seed_for_the_stool(capsys):
    assert main(["generate", "stool", "--size", "2", "--seed", "3"]) == 2
    assert "--seed applies to the random families" in capsys.readouterr().err
    assert main(["generate", "table", "--size", "1", "--tray", "300"]) == 2
    assert "expected WIDTHxHEIGHT" in capsys.readouterr().err
