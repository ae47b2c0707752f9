"""What every command shares: exit codes, argument types, shared options and error handling.

Argument types turn one command-line string into a value or raise
:class:`argparse.ArgumentTypeError`, so a bad value is a one-line usage error (exit 2) naming the
option. Only the standard library is imported here: ``bilevel-kit --help`` must stay fast.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from contextvars import ContextVar
from typing import IO, TYPE_CHECKING, Any, NoReturn, TypeVar

if TYPE_CHECKING:
    from contextlib import AbstractContextManager

    from ..experiments.cells import SweepSession
    from ..instance import Instance
    from ..options import Registered
    from ..paths import Output

EXIT_OK, EXIT_INVALID, EXIT_USAGE, EXIT_UNKNOWN = 0, 1, 2, 3
#: ``pack``: no layout on the chosen grid, which is not a proof that none exists.
EXIT_NO_GRID_LAYOUT = 4

#: The largest seed: CP-SAT takes 32-bit seeds, and every command's seed reaches one solver.
MAX_SEED = 2**31 - 1

#: A sweep finished but some of its cells failed (their error records say why).
EXIT_FAILED = 5
#: Ctrl-C or SIGTERM: the command stopped and cleaned up; a sweep keeps its finished cells
#: (128 + SIGINT, for SIGTERM too: one code for "interrupted", docs/cli.md#exit-codes).
EXIT_INTERRUPTED = 130
#: Every exit code a command uses, with its meaning: ``bilevel-kit --help`` lists them, and
#: the README's list is tested against this one (tests/cli/test_cli.py).
EXIT_CODES: dict[int, str] = {
    EXIT_OK: "ok",
    EXIT_INVALID: "invalid solution (check, solve --check, compare), a placement out of reach, "
    "or a plugin's method failed",
    EXIT_USAGE: "bad input or usage (one line on stderr, nothing written)",
    EXIT_UNKNOWN: "no definite answer within the time limit (compare: a method gave no plan)",
    EXIT_NO_GRID_LAYOUT: "pack: no layout on this grid, which is not a proof that none exists",
    EXIT_FAILED: "a sweep (compare, simulate, repro) finished but some cells failed",
    EXIT_INTERRUPTED: "interrupted by Ctrl-C or SIGTERM (a sweep keeps its finished cells; "
    "nothing else is written)",
}
#: The environment variable naming a running Dask scheduler (as Dask itself reads it).
SCHEDULER_ENV = "DASK_SCHEDULER_ADDRESS"

#: The instance fields the override options replace (see :func:`instance_overrides`).
OVERRIDES = ("delivery_time", "weights", "horizon", "units", "trays")

N = TypeVar("N", int, float)


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors (exit 2) instead of the usage dump.

    ``lazy_epilog``: a function giving text printed after the help, called only when the help
    is printed (it may import modules that parsing arguments must not pay for).
    """

    def __init__(self, *args: Any, lazy_epilog: Callable[[], str] | None = None, **kw: Any):
        super().__init__(*args, **kw)
        self.lazy_epilog = lazy_epilog

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see --help)\n")

    def format_help(self) -> str:
        text = super().format_help()
        return text if self.lazy_epilog is None else f"{text}\n{self.lazy_epilog()}\n"


def options_epilog(usage: str, policies: bool = False) -> str:
    """Every method's (``policies``: simulation policy's) option names, ``usage`` saying how
    to pass them; it imports the options dataclasses, hence a :class:`Parser` ``lazy_epilog``."""
    import shutil
    import textwrap

    from ..methods import REGISTRY

    specs: list[Registered] = list(REGISTRY.values())
    if policies:
        from ..sim.registry import POLICIES

        specs = [POLICIES.spec(n) for n in POLICIES]
    width = max(len(s.name) for s in specs) + 2
    columns = max(60, min(100, shutil.get_terminal_size().columns - 2))  # as argparse wraps
    what = "policy" if policies else "method"
    lines = textwrap.wrap(
        f"{what} options ({usage}); their types, defaults and meaning: bilevel-kit methods NAME",
        width=columns,
    )
    for spec in specs:
        names = ", ".join(i.name for i in spec.describe_options()) or "no options"
        lines += textwrap.wrap(
            names,
            width=columns,
            initial_indent=f"  {spec.name:<{width}}",
            subsequent_indent=" " * (width + 2),
            break_on_hyphens=False,
        )
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# Argument types
# ---------------------------------------------------------------------------------------------


def key_values(text: str) -> dict[str, str]:
    """``"a=1, b=2"`` as ``{"a": "1", "b": "2"}``."""
    out: dict[str, str] = {}
    for item in filter(None, (s.strip() for s in text.split(","))):
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {item!r}")
        out[key.strip()] = value.strip()
    return out


def weights(text: str) -> dict[str, float]:
    """``--weights W3=1,w4=2``: weight names upper-cased, values finite numbers >= 0."""
    return _number_map(
        text, lambda v: v >= 0 and math.isfinite(v), "a finite number >= 0, got {v!r}", str.upper
    )


def _checked(text: str, cast: Callable[[str], N], ok: Callable[[N], bool], what: str) -> N:
    """``cast(text)`` when that parses and passes ``ok``; else "expected WHAT, got TEXT"
    (WHAT names the kind: "an integer", "a number", then the range)."""
    kind = "an integer" if cast is int else "a number"
    try:
        v = cast(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {kind}, got {text!r}") from None
    if not ok(v):
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
    return v


def _number_map(
    text: str, ok: Callable[[float], bool], must: str, key: Callable[[str], str] = str
) -> dict[str, float]:
    """``k=v,...`` with every value a number passing ``ok``; else "K must be MUST" (MUST may
    use ``{v!r}``, the value as given)."""
    out = {}
    for k, v in key_values(text).items():
        try:
            out[key(k)] = value = float(v)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{k} must be a number, got {v!r}") from None
        if not ok(value):
            raise argparse.ArgumentTypeError(f"{k} must be " + must.format(v=v))
    return out


def seed(text: str) -> int:
    """A random seed: an integer in [0, 2^31 - 1] (the range every back-end accepts)."""
    return _checked(text, int, lambda v: 0 <= v <= MAX_SEED, f"an integer in [0, {MAX_SEED}]")


def length(text: str) -> float:
    """A length in mm in the instances' range [0.01, 1e5] (docs/formats.md#ranges)."""
    from ..instance import MAX_LENGTH, MIN_LENGTH

    return _checked(
        text,
        float,
        lambda v: MIN_LENGTH <= v <= MAX_LENGTH,
        f"a length in [{MIN_LENGTH:g}, {MAX_LENGTH:g}] mm",
    )


def positive(text: str) -> float:
    """A finite number > 0."""
    return _checked(text, float, lambda v: v > 0 and math.isfinite(v), "a finite number > 0")


def speed_scale(text: str) -> float:
    """A speed scale in (0, 1]."""
    return _checked(text, float, lambda v: 0 < v <= 1, "a number in (0, 1]")


def scalar(value: str) -> Any:
    """A loose option value: a boolean word, an int, a float, or else the string itself."""
    low = value.lower()
    if low in ("true", "yes", "on"):
        return True
    if low in ("false", "no", "off"):
        return False
    for cast in (int, float):
        try:
            return cast(value)
        except ValueError:
            pass
    return value


def param(text: str) -> tuple[str, Any]:
    """``--param KEY=VALUE`` as ``(key, value)``; dashes in the key become underscores."""
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"--param: expected KEY=VALUE, got {text!r}")
    return key.replace("-", "_"), scalar(value)


def float_map(text: str) -> dict[str, float]:
    """``leg=60,foot=60``: every value a finite number > 0."""
    return _number_map(text, lambda v: v > 0 and v != float("inf"), "a finite number > 0")


def nonneg(text: str) -> float:
    """A finite number >= 0 (times in seconds)."""
    return _checked(text, float, lambda v: v >= 0 and v != float("inf"), "a finite number >= 0")


def time_limit(text: str) -> float:
    """A time limit: seconds > 0 and at most :data:`bilevel_kit.methods.MAX_TIME_LIMIT`, the
    same range for every command and for :func:`bilevel_kit.methods.check_time_limit`."""
    from ..methods import MAX_TIME_LIMIT

    return _checked(
        text, float, lambda v: 0 < v <= MAX_TIME_LIMIT, f"seconds > 0 and <= {MAX_TIME_LIMIT:g}"
    )


def positive_int(text: str) -> int:
    """An integer >= 1 (counts)."""
    return _checked(text, int, lambda v: v >= 1, "an integer >= 1")


def listed(text: str, item: Callable[[str], N]) -> tuple[N, ...]:
    """``a,b,c``: one or more comma-separated values, each parsed and checked by ``item`` (one
    of the argument types here, e.g. :func:`positive_int`)."""
    values = tuple(item(s.strip()) for s in text.split(",") if s.strip())
    if not values:
        raise argparse.ArgumentTypeError("expected at least one value")
    return values


# ---------------------------------------------------------------------------------------------
# Shared options
# ---------------------------------------------------------------------------------------------


def add_seed(
    p: argparse.ArgumentParser, text: str = "random seed (default 0)", default: int | None = 0
) -> None:
    """``--seed N``, an integer >= 0 (:func:`seed`)."""
    p.add_argument("--seed", type=seed, default=default, metavar="N", help=text)


def add_time_limit(
    p: argparse.ArgumentParser, text: str, default: float | None = None, flag: str = "--time-limit"
) -> None:
    """``--time-limit S``, seconds in (0, 1e6] (:func:`time_limit`); None: the method's own."""
    p.add_argument(flag, type=time_limit, default=default, metavar="S", help=f"{text}; S > 0")


def add_resolution(p: argparse.ArgumentParser, text: str, default: float | None = None) -> None:
    """``--resolution MM``, a grid cell size in the instances' length range (:func:`length`)."""
    p.add_argument("--resolution", type=length, default=default, metavar="MM", help=text)


def add_output(
    p: argparse.ArgumentParser,
    *flags: str,
    folder: bool = False,
    figure: bool = False,
    writes: str | None = None,
    **kwargs: Any,
) -> None:
    """An output option: a file, a ``folder``, or a ``figure`` (a file whose suffix names its
    format); ``writes``: what the file holds when it is not text (a kind of
    :data:`bilevel_kit.paths.SIGNATURES`). :func:`run_command` checks its path
    (:mod:`bilevel_kit.paths`) before the command does any work, so a bad path costs nothing
    and writes nothing."""
    action = p.add_argument(*flags, **kwargs)
    key = "output_folders" if folder else "output_figures" if figure else "output_files"
    known = dict(p.get_default(key) or {})
    known[flags[0]] = action.dest
    p.set_defaults(**{key: known})
    if writes is not None:
        p.set_defaults(output_writes={**(p.get_default("output_writes") or {}), flags[0]: writes})


def add_derived_outputs(
    p: argparse.ArgumentParser, outputs: Callable[[argparse.Namespace], list[Output]]
) -> None:
    """The files and folders a command names itself (the bags in ``--bag DIR``): ``outputs``
    gives them from the arguments, and :func:`check_output_options` checks them with the
    output options, against each other and against existing files (docs/cli.md#output-paths)."""
    p.set_defaults(derived_outputs=outputs)


#: The arguments that name input files, wherever a command has them: no output may be one
#: of these files.
INPUTS = ("instance", "instances", "solution", "file")


def check_output_options(args: argparse.Namespace) -> None:
    """Every output the command will write (see :func:`add_output` and
    :func:`add_derived_outputs`), checked in one go against each other, against existing
    files and against the command's input files (:data:`INPUTS`)."""
    from ..paths import check_outputs

    def given(key: str) -> dict[str, Any]:
        return {opt: getattr(args, dest) for opt, dest in (getattr(args, key, None) or {}).items()}

    inputs: dict[str, Any] = {}
    for dest in INPUTS:
        value = getattr(args, dest, None)
        values = value if isinstance(value, list) else [value]
        inputs.update(
            {f"{dest} {i}" if len(values) > 1 else dest: v for i, v in enumerate(values, 1)}
        )
    derived = getattr(args, "derived_outputs", None)
    check_outputs(
        given("output_files"),
        given("output_folders"),
        figures=given("output_figures"),
        inputs={k: v for k, v in inputs.items() if isinstance(v, str)},
        writes=getattr(args, "output_writes", None),
        derived=[] if derived is None else derived(args),
    )


def add_param_option(p: argparse.ArgumentParser, text: str) -> None:
    """The repeatable ``--param/-p KEY=VALUE`` option (collected as ``(key, value)`` pairs)."""
    p.add_argument(
        "--param", "-p", type=param, action="append", default=[], metavar="KEY=VALUE", help=text
    )


def add_method_param_option(p: argparse.ArgumentParser) -> None:
    """The repeatable ``--param/-p METHOD:KEY=VALUE`` option of the commands that run several
    methods (read back by :func:`method_params`)."""
    p.add_argument(
        "--param",
        "-p",
        action="append",
        default=[],
        metavar="METHOD:KEY=VALUE",
        help="option for one method, e.g. greedy-ce:polish=true (repeatable)",
    )


def method_params(items: list[str], methods: list[str]) -> dict[str, dict[str, Any]]:
    """``--param METHOD:KEY=VALUE`` items as one option dict per method."""
    from ..errors import UsageError

    out: dict[str, dict[str, Any]] = {m: {} for m in methods}
    for item in items:
        method, sep, kv = item.partition(":")
        if not sep or method not in out:
            raise UsageError(
                f"--param {item!r}: expected METHOD:KEY=VALUE with METHOD one of "
                f"{', '.join(methods)}"
            )
        try:
            key, value = param(kv)
        except argparse.ArgumentTypeError as exc:
            raise UsageError(f"--param {item!r}: {exc}") from None
        out[method][key] = value
    return out


def add_delivery_time(p: argparse.ArgumentParser | argparse._ArgumentGroup, text: str) -> None:
    """``--d/--delivery-time S``."""
    p.add_argument(
        "--d", "--delivery-time", dest="delivery_time", type=nonneg, metavar="S", help=text
    )


def add_instance_overrides(p: argparse.ArgumentParser) -> None:
    """The ``instance overrides`` group; :func:`instance_overrides` reads it back."""
    g = p.add_argument_group("instance overrides")
    add_delivery_time(g, "delivery time d in seconds (overrides the instance)")
    g.add_argument(
        "--weights",
        type=weights,
        metavar="W3=1,W4=1",
        help="override some of the paper's weights W1..W7",
    )
    g.add_argument(
        "--horizon",
        type=positive_int,
        metavar="N",
        help="look-ahead N of the greedy upper level (default: the instance's, 5)",
    )
    g.add_argument(
        "--units",
        type=positive_int,
        metavar="U",
        help="number of product units built one after another",
    )
    g.add_argument(
        "--trays",
        type=trays,
        metavar="T",
        help="kit trays in circulation (an integer >= 1, or 'unlimited'); the paper's study: 1",
    )


def scheduler_address(text: str) -> str:
    """A Dask scheduler's address, ``[PROTOCOL://]HOST:PORT`` (what Dask itself requires:
    an address without a port fails only after Dask tried to connect)."""
    import re

    if not re.fullmatch(r"([a-z]+://)?(\[[0-9A-Fa-f:.]+\]|[^\s/:\[\]]+):\d{1,5}", text):
        raise argparse.ArgumentTypeError(f"expected [tcp://]HOST:PORT, got {text!r}")
    return text


def add_sweep_options(p: argparse.ArgumentParser, what: str = "cells") -> None:
    """``--jobs N``, ``--scheduler ADDRESS`` and ``-q``: where a sweep's cells run
    (docs/cluster.md); :func:`sweep_session` reads them back."""
    g = p.add_argument_group("running the sweep (docs/cluster.md)")
    g.add_argument(
        "--jobs",
        "-j",
        type=positive_int,
        default=1,
        metavar="N",
        help=f"run the {what} on N local worker processes (a Dask LocalCluster); "
        "1 (default): in this process",
    )
    g.add_argument(
        "--scheduler",
        type=scheduler_address,
        metavar="tcp://HOST:PORT",
        help=f"run the {what} on a running Dask cluster (default: ${SCHEDULER_ENV} if set); "
        "overrides --jobs",
    )
    g.add_argument(
        "-q", "--quiet", action="store_true", help="no progress bar (the summary line stays)"
    )


def sweep_session(args: argparse.Namespace) -> AbstractContextManager[SweepSession]:
    """The sweep session of the command's ``--jobs``/``--scheduler``/``-q``."""
    import os

    from ..experiments.cells import sweep_session as session

    scheduler = args.scheduler or os.environ.get(SCHEDULER_ENV) or None
    if scheduler is not None and not args.scheduler:
        from ..errors import UsageError

        try:
            scheduler_address(scheduler)
        except argparse.ArgumentTypeError as exc:
            raise UsageError(f"${SCHEDULER_ENV}: {exc}") from None
    return session(args.jobs, scheduler, progress=False if args.quiet else None, connect=True)


def sweep_exit(
    session: SweepSession, code: int, failed: int | None = None, all_failed: str | None = None
) -> int:
    """:data:`EXIT_FAILED`, with a line on stderr, when cells failed (``failed``, default:
    those computed in the session); it wins over ``code``: the results are incomplete.
    ``all_failed``: the line for a sweep whose every cell failed
    (:func:`~bilevel_kit.experiments.cells.all_failed_line`), said instead of the count."""
    n = session.failed if failed is None else failed
    if all_failed:
        print(all_failed, file=sys.stderr)
        return EXIT_FAILED
    if n:
        say(f"{n} cell(s) failed (see their error records)")
        return EXIT_FAILED
    return code


def trays(text: str) -> int | str:
    """``--trays``: an integer >= 1, or ``unlimited``."""
    if text.lower() in ("unlimited", "none"):
        return "unlimited"
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected an integer >= 1 or 'unlimited', got {text!r}"
        ) from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1 or 'unlimited', got {text!r}")
    return value


def instance_overrides(args: argparse.Namespace) -> dict[str, Any]:
    """The overrides given on the command line, as keyword arguments of
    :meth:`~bilevel_kit.instance.Instance.with_overrides` (options not given are left out)."""
    return {k: getattr(args, k) for k in OVERRIDES if getattr(args, k) is not None}


def load_instance(args: argparse.Namespace) -> Instance:
    """``args.instance`` loaded, with the command-line overrides applied."""
    from ..instance import load

    return load(args.instance).with_overrides(**instance_overrides(args))


# ---------------------------------------------------------------------------------------------
# Output and errors
# ---------------------------------------------------------------------------------------------


def print_violations(lines: list[str], stream: IO[str], limit: int = 20, per_kind: int = 3) -> None:
    """``INVALID: n violation(s)`` and the violations, root causes first (the checker lists
    kinds in that order: a precedence or parts error before the kit times it shifts). When
    there are more than ``limit``, each kind shows its first ``per_kind`` lines and a count
    of the rest, so one root cause is never buried under its consequences."""
    print(f"INVALID: {len(lines)} violation(s)", file=stream)
    if len(lines) <= limit:
        for line in lines:
            print(f"  {line}", file=stream)
        return
    groups: dict[str, list[str]] = {}
    for line in lines:
        kind = line[1 : line.index("]")] if line.startswith("[") and "]" in line else ""
        groups.setdefault(kind, []).append(line)
    for kind, group in groups.items():
        for line in group[:per_kind]:
            print(f"  {line}", file=stream)
        if len(group) > per_kind:
            print(f"  ... and {len(group) - per_kind} more [{kind}]", file=stream)


#: The command running (set by :func:`run_command`): :func:`say` names it.
_COMMAND: ContextVar[str] = ContextVar("command", default="")


def prefix(command: str | None = None) -> str:
    """``bilevel-kit COMMAND:``, how every line a command writes about a failure starts (the
    one place it is spelt; argparse's own errors start with the parser's ``prog``, the same
    words); ``command`` None: the running one."""
    name = _COMMAND.get() if command is None else command
    return f"bilevel-kit {name}:" if name else "bilevel-kit:"


def say(text: str, stream: IO[str] | None = None) -> None:
    """``text`` on stderr (or ``stream``) after :func:`prefix`: a failed cell, an invalid
    plan, a hint, each a line of its own."""
    print(f"{prefix()} {text}", file=sys.stderr if stream is None else stream, flush=True)


def run_command(
    name: str, run: Callable[[argparse.Namespace], int], args: argparse.Namespace
) -> int:
    """Run one command: a library error is one line on stderr and exit 2, no traceback; an
    interrupt (Ctrl-C, or SIGTERM under :func:`bilevel_kit.interrupt.signal_guard`) is one
    line and exit 130 once every cleanup on the way has run."""
    from ..errors import BilevelKitError, PluginError, one_line
    from ..interrupt import checkpoint, report

    token = _COMMAND.set(name)
    try:
        check_output_options(args)
        return run(args)
    except BilevelKitError as exc:
        checkpoint()  # after a signal an error is the interrupt's, reported as it (main)
        say(f"error: {one_line(exc)}")
        # a plugin's method failed on good input: not a usage error (docs/extending.md#plugins)
        return EXIT_INVALID if isinstance(exc, PluginError) else EXIT_USAGE
    except KeyboardInterrupt as exc:
        report(exc, sys.stderr)
        return EXIT_INTERRUPTED
    finally:
        _COMMAND.reset(token)
