"""Part feeders: Poisson arrivals into a stock, interrupted by machine failures.

A feeder is one SimPy process per part type that has a supply process (types without one are
always available and have no feeder). It alternates two phases:

* **up** for an exponential time with mean ``MTTF`` (forever when MTTF is None); during it
  parts arrive as a Poisson process with mean inter-arrival ``MAT``, each arrival adding one
  part to the stock;
* **broken** for the fixed ``repair_time`` (30 s by default); no part arrives.

Exactly how a failure interrupts an arrival: the inter-arrival time in progress when the machine
fails is *discarded*, and after the repair a fresh exponential inter-arrival time is drawn from
the moment the machine is up again. By memorylessness this is the same law as resuming the
residual time, so over a long run the arrival rate is ``(1 / MAT) * MTTF / (MTTF + repair)``
and the fraction of time broken is ``repair / (MTTF + repair)``. The time to the next failure
runs only while the machine is up (a fresh exponential after each repair).

The stock is unbounded and starts at ``initial`` parts (0 unless the caller says otherwise:
the paper's parts "arrive" at the robot's workspace, so a supplied type starts empty). The robot
is the only consumer; it waits on :meth:`Feeder.arrival` when the stock is empty.

Each feeder draws from its own random stream, so its sample path does not depend on what the
robot does (the same seed gives every policy the same arrivals).
"""

from __future__ import annotations

import math
from collections.abc import Generator
from typing import Any

import numpy as np
import simpy

from ..instance import Supply


class Feeder:
    """The supply process and stock of one part type (see the module docstring)."""

    def __init__(
        self,
        env: simpy.Environment,
        part_type: str,
        supply: Supply,
        rng: np.random.Generator,
        initial: int = 0,
    ) -> None:
        if not (math.isfinite(supply.mat) and supply.mat > 0):
            raise ValueError(f"feeder {part_type!r}: MAT must be finite and > 0")
        if supply.mttf is not None and not (math.isfinite(supply.mttf) and supply.mttf > 0):
            raise ValueError(f"feeder {part_type!r}: MTTF must be finite and > 0")
        if supply.repair_time < 0 or initial < 0:
            raise ValueError(f"feeder {part_type!r}: repair time and initial stock must be >= 0")
        self.env = env
        self.part_type = part_type
        self.supply = supply
        self.rng = rng
        self.stock = int(initial)
        self.initial = int(initial)
        self.arrivals = 0
        self.failures = 0
        self.consumed = 0
        self.broken = False
        #: time of every arrival, in order (for tests and plots)
        self.arrival_times: list[float] = []
        self._broken_total = 0.0  # closed repair periods
        self._broken_since = 0.0
        self._arrival_event: simpy.Event | None = None
        self.process = env.process(self._run())

    # -- the process ---------------------------------------------------------------------------
    def _run(self) -> Generator[simpy.Event, Any, None]:
        env, rng, s = self.env, self.rng, self.supply
        while True:
            up_end = env.now + rng.exponential(s.mttf) if s.mttf is not None else math.inf
            while True:
                gap = rng.exponential(s.mat)
                if env.now + gap >= up_end:
                    yield env.timeout(up_end - env.now)  # the gap in progress is discarded
                    break
                yield env.timeout(gap)
                self._arrive()
            self.failures += 1
            self.broken = True
            self._broken_since = env.now
            yield env.timeout(s.repair_time)
            self.broken = False
            self._broken_total += env.now - self._broken_since

    def _arrive(self) -> None:
        self.stock += 1
        self.arrivals += 1
        self.arrival_times.append(self.env.now)
        ev = self._arrival_event
        if ev is not None:
            self._arrival_event = None
            ev.succeed()

    # -- the consumer's side ---------------------------------------------------------------------
    def arrival(self) -> simpy.Event:
        """An event that fires at the next arrival (shared by everyone waiting now)."""
        if self._arrival_event is None:
            self._arrival_event = self.env.event()
        return self._arrival_event

    def take(self) -> None:
        """Remove one part from the stock (the caller checked that there is one)."""
        if self.stock <= 0:
            raise RuntimeError(f"feeder {self.part_type!r}: take() from an empty stock")
        self.stock -= 1
        self.consumed += 1

    # -- statistics --------------------------------------------------------------------------
    def time_broken(self) -> float:
        """Total time spent under repair up to now (including a repair in progress)."""
        extra = self.env.now - self._broken_since if self.broken else 0.0
        return self._broken_total + extra

    def repair_remaining(self) -> float:
        """Seconds until the machine is up again (0 when it is up)."""
        if not self.broken:
            return 0.0
        return max(0.0, self._broken_since + self.supply.repair_time - self.env.now)

    def expected_time_to_arrival(self) -> float:
        """Expected time until the next part arrives, from the current state.

        While up, the next event is an arrival (rate 1/MAT) or a failure (rate 1/MTTF), and a
        failure costs the repair time and starts over: ``E = MAT * (1 + repair / MTTF)``
        (exact for this process). While broken, add the repair time still to go.
        """
        return self.repair_remaining() + self.supply.cycle

    def stats(self) -> dict[str, float | int]:
        """Counters for tests and run records (JSON-serialisable)."""
        return {
            "arrivals": self.arrivals,
            "failures": self.failures,
            "time_broken": self.time_broken(),
            "consumed": self.consumed,
            "stock": self.stock,
            "initial": self.initial,
        }
