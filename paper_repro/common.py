"""Shared helpers of the ``paper_repro`` scripts: import path, common options, printing.

The reproduction logic lives in :mod:`bilevel_kit.repro` (so that the installed CLI,
``bilevel-kit repro user-study|fig6``, can run it); these scripts are thin wrappers that also
work from a plain checkout without installing the package.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def ensure_importable() -> None:
    """Put the repository root on ``sys.path`` when ``bilevel_kit`` is not installed."""
    try:
        import bilevel_kit  # noqa: F401
    except ImportError:
        sys.path.insert(0, str(ROOT))


def base_parser(description: str, default_out: str) -> argparse.ArgumentParser:
    """Options every script takes: --out, --quick, --seed, --jobs."""
    p = argparse.ArgumentParser(description=description)
    p.add_argument("--out", default=default_out, help=f"output folder (default {default_out})")
    p.add_argument("--quick", action="store_true", help="reduced run for tests (seconds)")
    p.add_argument("--seed", type=int, default=0, help="base seed (default 0)")
    p.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    return p


def print_files(result: dict) -> None:
    """List what a run wrote."""
    for name, path in result.get("files", {}).items():
        print(f"  {name:<12} {path}")
