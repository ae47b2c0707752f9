"""The ``simulate --reps`` cells: one replication (one seed) of the shop-floor simulation.

Why cells: the replications of ``bilevel-kit simulate`` run through the one cell runner
(:mod:`.cells`), so ``--jobs``/``--scheduler`` spread them over workers (docs/cluster.md).
The records equal :func:`bilevel_kit.sim.replicate`'s: with a fixed ``params.policy_seed``
one policy object serves every run of a process (:func:`_shared_policy`), exactly as
``replicate`` shares it between its runs (docs/simulation.md).
"""

from __future__ import annotations

import hashlib
import pickle
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..instance import Instance
    from ..sim import Policy, SimParams

#: Policies kept per process, by digest of (instance, policy name, params).
_POLICIES: dict[str, Policy] = {}
_MAX_POLICIES = 4


@dataclass(frozen=True)
class ReplicationCell:
    """One run of ``policy`` on ``instance`` with ``params`` and ``seed``."""

    instance: Instance
    policy: str
    params: SimParams
    seed: int

    def key(self) -> str:
        return f"{self.policy}__s{self.seed}"


def _shared_policy(cell: ReplicationCell) -> str | Policy:
    """The process's policy object for the cell's (instance, policy, params), as
    :func:`~bilevel_kit.sim.replicate` builds it; the name when ``policy_seed`` is None."""
    from ..sim import effective_instance, make_policy

    params = cell.params
    if params.policy_seed is None:
        return cell.policy
    digest = hashlib.sha1(pickle.dumps((cell.instance, cell.policy, params))).hexdigest()
    if digest not in _POLICIES:
        if len(_POLICIES) >= _MAX_POLICIES:
            _POLICIES.pop(next(iter(_POLICIES)))
        inst = effective_instance(cell.instance, params)
        _POLICIES[digest] = make_policy(cell.policy, inst, seed=params.policy_seed, params=params)
    return _POLICIES[digest]


def replication_cell(cell: ReplicationCell) -> dict[str, Any]:
    """The record of one run (:func:`bilevel_kit.sim.run`)."""
    from ..sim import run

    return run(cell.instance, _shared_policy(cell), params=cell.params, seed=cell.seed)
