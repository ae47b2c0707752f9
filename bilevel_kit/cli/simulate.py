"""``bilevel-kit simulate``: replications of the shop-floor simulation of one policy.

Values are checked where they are used: the policy name by the simulation's policy registry,
``--trays`` (an instance override, docs/timeline.md) by its argument type; both are one-line
usage errors (exit 2). The removed ``--buffer K`` is an error that names its replacement,
``--trays K+1``.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..instance import Instance

from .common import (
    EXIT_OK,
    add_instance_overrides,
    add_output,
    add_param_option,
    add_seed,
    add_sweep_options,
    float_map,
    instance_overrides,
    nonneg,
    positive_int,
    say,
    sweep_exit,
    sweep_session,
)

#: The metrics summarised on stdout (mean, sd, min, max over the replications).
SIM_COLUMNS = (
    "makespan",
    "human_idle",
    "robot_idle",
    "n_kits",
    "robot_wait",
    "n_waits",
    "robot_blocked",
)
#: The columns of ``--csv`` after ``instance`` and ``policy``.
CSV_COLUMNS = ("seed", "units", *SIM_COLUMNS, "human_work", "robot_work", "max_queue")


#: How ``-p`` is spelled here; the help lists every policy's keys after it.
PARAM_USAGE = "-p KEY=VALUE"
PARAM_POLICIES = True


HELP = "shop-floor simulation (SimPy) of a kitting policy"
DESCRIPTION = (
    "Replications of the paper's shop-floor simulation (Section V-B): feeders with Poisson "
    "arrivals (mean inter-arrival MAT) and exponential failures (MTTF, fixed repair), the robot "
    "asking its policy for the next kit at each epoch, the human assembling with sampled "
    "participant times. Replication r uses seed SEED + r. --jobs/--scheduler run the "
    "replications in parallel (docs/cluster.md); exit 5 when a replication failed."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("instance")
    p.add_argument(
        "--policy",
        metavar="NAME",
        help="single-task | whole-assembly | optimized | cpsat-rolling | optimized-adaptive | "
        "cpsat-rolling-adaptive | optimized-oracle | cpsat-rolling-oracle | fixed-plan "
        "(default optimized; fixed-plan with --plan)",
    )
    p.add_argument(
        "--plan",
        metavar="SOLUTION",
        help="run this solution file's kits (solve -o) in its order, never re-planned "
        "(policy fixed-plan); checked against the simulated instance first",
    )
    p.add_argument(
        "--mean-times",
        action="store_true",
        help="no sampling: every task takes its mean human time, every pick its pick time",
    )
    p.add_argument(
        "--mat",
        type=float_map,
        default={},
        metavar="leg=60,foot=60",
        help="mean inter-arrival time (s) per part type; other types always there",
    )
    p.add_argument("--mttf", type=nonneg, metavar="S", help="mean time to failure of feeders")
    p.add_argument("--repair", type=nonneg, metavar="S", help="repair time (default 30 s)")
    # removed: the tray limit is the instance's ``trays`` (--trays); kept only to say so
    p.add_argument("--buffer", help=argparse.SUPPRESS)
    p.add_argument("--reps", type=positive_int, default=30, help="replications (default 30)")
    add_seed(p, "seed of the first replication (default 0)")
    add_output(p, "--csv", metavar="FILE", help="one row per replication")
    add_instance_overrides(p)
    add_param_option(p, "policy option, e.g. cpsat-rolling: window=12, time_limit=1 (repeatable)")
    add_sweep_options(p, "replications")


def run(args: argparse.Namespace) -> int:
    from ..errors import UsageError
    from ..experiments.cells import is_failed, run_cells
    from ..experiments.replications import ReplicationCell, replication_cell
    from ..instance import load
    from ..sim import POLICIES, SimParams, TimingModel
    from ..sim.stations import require_station_policy

    if args.buffer is not None:
        raise UsageError("--buffer was removed: use --trays (trays = buffer + 1)")
    instance = load(args.instance)
    # the simulation rejects unknown part types too, but without naming --mat; an MTTF with
    # no feeder to fail it would silently do nothing
    unknown = sorted(set(args.mat) - set(instance.part_types))
    if unknown:
        raise UsageError(f"--mat: unknown part type(s) {', '.join(unknown)}")
    if args.mttf is not None and not args.mat and not instance.supply:
        raise UsageError("--mttf needs feeders: give --mat or an instance 'supply' section")
    args.policy = _resolve_plan(args)
    params = SimParams(
        **instance_overrides(args),
        mat=args.mat,
        mttf=args.mttf,
        repair_time=args.repair,
        policy_options=dict(args.param),
        timing=TimingModel.deterministic() if args.mean_times else TimingModel(),
    )
    POLICIES.spec(args.policy).parse(params.policy_options)  # fail before any run
    require_station_policy(instance, args.policy)  # several stations: exit 2 before any run
    if args.plan:  # the plan checked against the simulated instance, before any run
        from ..sim import effective_instance
        from ..sim.fixed import load_plan

        load_plan(args.plan, effective_instance(instance, params))
    cells = [
        ReplicationCell(instance, args.policy, params, s)
        for s in range(args.seed, args.seed + args.reps)
    ]
    from .solve import prepare

    prepare([args.policy])
    with sweep_session(args) as session:
        records = run_cells(cells, replication_cell, desc=f"simulate {args.policy}")
    failed = [r for r in records if is_failed(r)]
    for r in failed:
        say(f"replication {r['cell']['seed']}: {r['error']}")
    records = [r for r in records if not is_failed(r)]
    if not records:
        return sweep_exit(session, EXIT_OK)
    _print_summary(instance.name, args, records)
    if not args.mean_times:
        _say_sampled(instance, records)
    if args.csv:
        from ..experiments import write_csv

        rows = [
            {
                "instance": instance.name,
                "policy": args.policy,
                **{k: r[k] for k in CSV_COLUMNS},
                **station_columns(r),
            }
            for r in records
        ]
        write_csv(args.csv, rows)
    return sweep_exit(session, EXIT_OK)


def _resolve_plan(args: argparse.Namespace) -> str:
    """The policy: ``--plan FILE`` is ``fixed-plan`` with ``plan=FILE`` (docs/simulation.md)."""
    from ..errors import UsageError

    policy = args.policy or ("fixed-plan" if args.plan else "optimized")
    if args.plan is None:
        return str(policy)
    if policy != "fixed-plan":
        raise UsageError(f"--plan runs the fixed-plan policy, not {policy!r}: drop --policy")
    if any(k.replace("-", "_") == "plan" for k, _ in args.param):
        raise UsageError("give the plan once: --plan FILE or -p plan=FILE")
    args.param = [*args.param, ("plan", args.plan)]
    return "fixed-plan"


def _say_sampled(instance: Instance, records: list[dict[str, Any]]) -> None:
    """Why a replication can beat a proven optimum: the simulation samples each task's human
    time (docs/simulation.md), while ``solve``'s plans, bounds and optima use the mean times."""
    print(
        "note: human times are sampled per replication (docs/simulation.md); solve's plans,\n"
        "  bounds and optima use the mean times, so a replication can end below them"
    )
    if records[0]["units"] != 1:
        return
    from ..bounds import best_bound

    bound = best_bound(instance)
    below = sum(float(r["makespan"]) < bound - 1e-9 for r in records)
    if below:
        print(
            f"  {below} of {len(records)} replication(s) ended below the mean-time lower bound "
            f"{bound:.2f} s: their humans were faster than the means"
        )


#: Each summary row's unit and meaning, printed under the table (docs/simulation.md).
SIM_LEGEND = {
    "makespan": ("s", "until the human finishes the last task"),
    "human_idle": ("s", "the human waiting for a kit"),
    "robot_idle": ("s", "the robot not kitting (includes robot_wait and robot_blocked)"),
    "n_kits": ("", "kits delivered"),
    "robot_wait": ("s", "the robot waiting for a feeder to deliver a missing part"),
    "n_waits": ("", "times the robot had to wait for a part"),
    "robot_blocked": ("s", "the robot waiting for a tray to come back (the trays limit)"),
}


#: Each station's metrics (docs/timeline.md#several-stations), as ``STATION_METRIC`` columns.
STATION_METRICS = ("completion", "human_idle", "n_kits")


def station_columns(record: dict[str, Any]) -> dict[str, Any]:
    """A replication's per-station metrics as ``STATION_METRIC`` columns (none for one
    station), in the file's station order."""
    return {
        f"{s}_{m}": values[m]
        for s, values in record.get("stations", {}).items()
        for m in STATION_METRICS
    }


def _print_summary(name: str, args: argparse.Namespace, records: list[dict[str, Any]]) -> None:
    import statistics

    units = records[0]["units"]
    stations = list(records[0].get("stations", {}))
    print(f"{name}: policy {args.policy}, {units} unit(s), {args.reps} replication(s)")
    per_station = [f"{s}_{m}" for s in stations for m in STATION_METRICS]
    rows = [{**r, **station_columns(r)} for r in records]
    for col in (*SIM_COLUMNS, *per_station):
        vals = [float(r[col]) for r in rows]
        sd = statistics.stdev(vals) if len(vals) > 1 else 0.0
        unit = SIM_LEGEND[col][0] if col in SIM_LEGEND else "" if col.endswith("n_kits") else "s"
        label = f"{col} ({unit})" if unit else col
        print(
            f"  {label:<18} mean {statistics.fmean(vals):10.2f}   sd {sd:9.2f}   "
            f"min {min(vals):10.2f}   max {max(vals):10.2f}"
        )
    print("where:")
    for col in SIM_COLUMNS:
        meaning = SIM_LEGEND[col][1]
        if stations and col == "human_idle":
            meaning = (
                f"the {len(stations)} humans waiting for a kit, summed over the stations "
                "(each up to its own completion), so it can exceed the makespan"
            )
        elif stations and col == "makespan":
            meaning = "until the last station's human finishes (the largest completion)"
        print(f"  {col:<14} {meaning}")
    if stations:
        print(
            f"  {'S_completion':<14} when station S's human finishes its last task; "
            "S_human_idle: that human waiting for a kit; S_n_kits: kits delivered to S"
        )
