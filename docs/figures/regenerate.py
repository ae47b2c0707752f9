"""Redraw committed figures from the commands of docs/figures/MANIFEST.json and rewrite their
digests (docs/figures.md#committed-figures-and-their-manifest).

    python docs/figures/regenerate.py                 # every stale figure with a quick command
    python docs/figures/regenerate.py NAME [NAME ...] # these figures (e.g. tutorial-compare.png)
    python docs/figures/regenerate.py --long NAME     # also figures whose command runs for long
    python docs/figures/regenerate.py --stamp NAME    # redrawn by hand: record the digests only
    python docs/figures/regenerate.py --check         # list the problems; exit 1 if any

Each manifest entry names the command that draws the figure (``bilevel-kit ...`` or
``python ...``, run from the repository root; ``{out}`` is a scratch folder), the file it
writes (``writes``: copied over the committed figure when it lies elsewhere) or the fenced
``python`` block of a docs page that draws it (``snippet``: ``docs/PAGE.md#heading``), how long
it runs (``cost``: quick, long or manual) and the SHA-256 of its inputs and of the code it
depends on. A figure whose digests no longer match is stale; ``stale_known`` lists the figures
known to be stale with the reason, and may only shrink (tests/core/test_figure_manifest.py).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
MANIFEST = ROOT / "docs" / "figures" / "MANIFEST.json"
#: Where committed figures live; every one of them needs a manifest entry.
FIGURE_GLOBS = ("docs/figures/*.png", "docs/figures/*.svg", "paper_repro/**/*.png")
#: How a command's first word runs here: the package of this checkout, this interpreter.
HEADS = {"bilevel-kit": [sys.executable, "-m", "bilevel_kit.cli"], "python": [sys.executable]}


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def load() -> dict:
    return json.loads(MANIFEST.read_text(encoding="utf-8"))


def save(manifest: dict) -> None:
    MANIFEST.write_text(json.dumps(manifest, indent=2, sort_keys=True) + "\n", encoding="utf-8")


def committed_figures() -> list[str]:
    """The figure files of the repository, as paths relative to its root."""
    return sorted({str(p.relative_to(ROOT)) for g in FIGURE_GLOBS for p in ROOT.glob(g)})


def how_to_rerun(name: str, entry: dict) -> str:
    """The command that redraws a figure, as the messages print it."""
    what = entry.get("snippet") or entry["command"]
    return f"{what} (or: python docs/figures/regenerate.py {Path(name).name})"


def changed(entry: dict) -> list[str]:
    """The inputs and code files of an entry whose digest no longer matches."""
    digests = {**entry["inputs"], **entry["code"]}
    return [f for f, d in digests.items() if (ROOT / f).is_file() and sha256(ROOT / f) != d]


def problems(manifest: dict) -> list[str]:
    """Every way the committed figures and the manifest disagree, one message each: a figure
    without an entry, an entry naming a missing file, a digest that no longer matches (the
    figure is stale unless ``stale_known`` says so)."""
    entries, stale = manifest["figures"], manifest.get("stale_known", {})
    out = [
        f"{f}: committed figure without a manifest entry in docs/figures/MANIFEST.json"
        for f in committed_figures()
        if f not in entries
    ]
    out += [f"stale_known names {n}, which has no entry" for n in stale if n not in entries]
    for name, entry in sorted(entries.items()):
        files = [name, *entry["inputs"], *entry["code"]]
        if entry.get("snippet"):
            files.append(entry["snippet"].split("#")[0])
        out += [
            f"{name}: names {f}, which does not exist" for f in files if not (ROOT / f).is_file()
        ]
        if name not in stale and changed(entry):
            out.append(
                f"{name} is stale: {', '.join(changed(entry))} changed since it was drawn; "
                f"rerun {how_to_rerun(name, entry)}"
            )
    return out


def snippet_code(ref: str) -> str:
    """The first fenced ``python`` block under the heading ``ref`` (``docs/PAGE.md#anchor``)."""
    page, anchor = ref.split("#")
    text = (ROOT / page).read_text(encoding="utf-8")
    for heading in re.finditer(r"^#+ (.+)$", text, re.M):
        if re.sub(r"[^a-z0-9 -]", "", heading.group(1).lower()).replace(" ", "-") == anchor:
            block = re.search(r"```python\n(.*?)```", text[heading.end() :], re.S)
            if block:
                return block.group(1)
    raise SystemExit(f"{ref}: no python block under that heading")


def run(name: str, entry: dict, out: Path) -> None:
    """Run the entry's command (its steps joined by ``&&``) from the repository root and put
    its figure in place."""
    if entry.get("snippet"):
        steps = [[sys.executable, "-c", snippet_code(entry["snippet"])]]
    else:
        words = [shlex.split(s) for s in entry["command"].replace("{out}", str(out)).split("&&")]
        steps = [HEADS.get(w[0], w[:1]) + w[1:] for w in words]
    print("$", entry.get("snippet") or entry["command"], flush=True)
    for argv in steps:
        subprocess.run(argv, cwd=ROOT, check=True)
    if entry.get("writes"):
        shutil.copyfile(Path(entry["writes"].replace("{out}", str(out))), ROOT / name)


def stamp(manifest: dict, name: str) -> None:
    """Record the current digests of a figure's inputs and code; it is no longer stale."""
    entry = manifest["figures"][name]
    for group in ("inputs", "code"):
        entry[group] = {f: sha256(ROOT / f) for f in entry[group]}
    manifest.get("stale_known", {}).pop(name, None)


def _selected(manifest: dict, names: list[str], long: bool) -> list[str]:
    """The entries named (by path or file name), or else every stale one that may run."""
    entries = manifest["figures"]
    by_file = {Path(n).name: n for n in entries}
    if names:
        unknown = [n for n in names if n not in entries and n not in by_file]
        if unknown:
            raise SystemExit(f"no manifest entry for {', '.join(unknown)}")
        return [n if n in entries else by_file[n] for n in names]
    costs = ("quick", "long") if long else ("quick",)
    return sorted(
        n
        for n, e in entries.items()
        if e["cost"] in costs and (n in manifest.get("stale_known", {}) or changed(e))
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("names", nargs="*", help="figures (file names); default: stale quick ones")
    parser.add_argument("--long", action="store_true", help="also run commands that run long")
    parser.add_argument("--stamp", action="store_true", help="record digests, run nothing")
    parser.add_argument("--check", action="store_true", help="list the problems, exit 1 if any")
    args = parser.parse_args(argv)
    manifest = load()
    if args.check:
        found = problems(manifest)
        print("\n".join(found) or "every committed figure matches its manifest entry")
        return 1 if found else 0
    names = _selected(manifest, args.names, args.long)
    done: set[str] = set()  # commands already run (one command may draw several figures)
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            entry = manifest["figures"][name]
            key = entry.get("snippet") or entry["command"]
            if not args.stamp and key not in done:
                if entry["cost"] == "manual":
                    raise SystemExit(f"{name}: drawn by hand ({entry['command']}); use --stamp")
                if entry["cost"] == "long" and not args.long:
                    raise SystemExit(f"{name}: its command runs long; add --long to run it")
                run(name, entry, Path(tmp))
                done.add(key)
            elif not args.stamp and entry.get("writes"):
                shutil.copyfile(Path(entry["writes"].replace("{out}", tmp)), ROOT / name)
            stamp(manifest, name)
            print(f"recorded {name}")
    save(manifest)
    return 0


if __name__ == "__main__":
    sys.exit(main())
