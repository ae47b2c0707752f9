"""Shop-floor simulation (paper Section V-B): feeders, robot and human as SimPy processes.

>>> from bilevel_kit import load
>>> from bilevel_kit.sim import SimParams, run
>>> rec = run(load("instances/hrc_table.json"), "single-task",
...           params=SimParams(units=2, mat={"leg": 60, "foot": 60}, mttf=90), seed=0)
>>> rec["n_kits"]
24

* :func:`run` / :func:`simulate` / :func:`replicate` (:mod:`.runs`): pure functions of
  (instance, policy, :class:`SimParams` (:mod:`.params`), seed).
* Policies: :data:`POLICIES` (:mod:`.registry`: ``single-task``, ``whole-assembly``,
  ``optimized`` in :mod:`.policies`, ``cpsat-rolling`` in :mod:`.cpsat_rolling`), the
  :class:`Policy` protocol and the :class:`SimState` they decide from (:mod:`.state`).
* :class:`TimingModel` (:mod:`.timing`): sampled participants and robot pick times, with
  calibration knobs.
* :class:`Feeder` (:mod:`.feeders`): the supply process of one part type; the engine that runs
  the processes is :mod:`.shopfloor`.
"""

from .feeders import Feeder
from .params import SimParams, effective_instance, resolve_supply
from .policies import OptimizedPolicy, SingleTaskPolicy, WholeAssemblyPolicy
from .registry import POLICIES, PolicySpec, make_policy
from .runs import SimResult, replicate, run, simulate
from .shopfloor import SimulationError
from .state import UNLIMITED, Policy, SimState
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
    "PolicySpec",
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
