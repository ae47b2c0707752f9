"""Shop-floor simulation (paper Section V-B): feeders, robot and human as SimPy processes.

>>> from bilevel_kit import load
>>> from bilevel_kit.sim import SimParams, run
>>> rec = run(load("instances/hrc_table.json"), "single-task",
...           params=SimParams(units=2, mat={"leg": 60, "foot": 60}, mttf=90), seed=0)
>>> rec["n_kits"]
24

* :func:`run` / :func:`simulate` / :func:`replicate`: pure functions of
  (instance, policy, :class:`SimParams`, seed).
* Policies: :data:`POLICIES` (``single-task``, ``whole-assembly``, ``optimized``), the
  :class:`Policy` protocol and the :class:`SimState` they decide from.
* :class:`TimingModel`: sampled participants and robot pick times, with calibration knobs.
* :class:`Feeder`: the supply process of one part type.
"""

from .feeders import Feeder
from .policies import (
    POLICIES,
    UNLIMITED,
    OptimizedPolicy,
    Policy,
    SimState,
    SingleTaskPolicy,
    WholeAssemblyPolicy,
    make_policy,
)
from .shopfloor import (
    SimParams,
    SimResult,
    SimulationError,
    effective_instance,
    replicate,
    resolve_supply,
    run,
    simulate,
)
from .timing import PAPER_CV, PAPER_TABLE_MEAN, PAPER_TABLE_SD, SampledTimes, TimingModel

__all__ = [
    "PAPER_CV",
    "PAPER_TABLE_MEAN",
    "PAPER_TABLE_SD",
    "POLICIES",
    "UNLIMITED",
    "Feeder",
    "OptimizedPolicy",
    "Policy",
    "SampledTimes",
    "SimParams",
    "SimResult",
    "SimState",
    "SimulationError",
    "SingleTaskPolicy",
    "TimingModel",
    "WholeAssemblyPolicy",
    "effective_instance",
    "make_policy",
    "replicate",
    "resolve_supply",
    "run",
    "simulate",
]
