"""Toy cells for the cell runner's tests (tests/experiments/): a number whose key is a prefix
and the number, and two cell functions, one of which raises on 0."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar


@dataclass(frozen=True)
class Toy:
    x: int

    prefix: ClassVar[str] = "toy"

    def key(self) -> str:
        return f"{self.prefix}{self.x}"


class Square(Toy):
    prefix = "sq"


class Div(Toy):
    prefix = "div"


def square(cell: Toy) -> dict[str, int]:
    return {"x": cell.x, "y": cell.x * cell.x}


def invert(cell: Toy) -> dict[str, float]:
    return {"x": cell.x, "y": 1 / cell.x}
