"""Entry point of the ``inserr`` command.

Each sub-command lives in its own module ``inserr.cli.<name>`` exposing
``HELP`` (one line), ``add_arguments(parser)`` and ``run(args) -> int``. Modules are
imported only when their command runs, so ``inserr modes`` does not pay for
matplotlib or dask.
"""

from __future__ import annotations

import argparse
import importlib
import signal
import sys
import threading
from contextlib import contextmanager

from inserr.core.errors import InputError

#: command name -> (module, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "modes": ("inserr.cli.modes", "Eigen-periods (Schuler, Foucault, Earth) of the error model."),
    "drift": ("inserr.cli.drift", "Free-inertial drift of an IMU budget under an indexing scheme."),
    "run": ("inserr.cli.run", "Run a scenario file and write a report directory."),
    "cycle": ("inserr.cli.cycle", "Closed-form cycle integrals of an indexing scheme."),
    "compare": ("inserr.cli.compare", "Compare indexing schemes on one scenario."),
    "validate": ("inserr.cli.validate", "Linear prediction vs nonlinear strapdown reference."),
    "observability": ("inserr.cli.observability", "Piecewise-constant observability analysis."),
    "align": ("inserr.cli.align", "Kalman-filter alignment study (static or indexed)."),
    "calibrate": ("inserr.cli.calibrate", "Multi-position gyro/accelerometer calibration."),
    "northfind": ("inserr.cli.northfind", "Rotation-modulation north finder (1 gyro, 1 accel)."),
    "sweep": ("inserr.cli.sweep", "Parameter sweep of a scenario on Dask."),
    "design": ("inserr.cli.design", "Design an indexing schedule robust to the vehicle's motion."),
    "imu-budget": (
        "inserr.cli.imu_budget",
        "IMU noise terms (ARW, bias instability, RRW) from a static recording (Allan deviation).",
    ),
}


#: Commands whose ``--out`` is not a report directory replaced as a whole (a sweep's and a
#: design's directories are resumable stores: :func:`inserr.sweep.store.check_sweep_dir`,
#: :func:`inserr.design.study.check_design_dir`).
_OWN_OUT_CHECK = frozenset({"sweep", "design"})


def available_commands() -> dict[str, tuple[str, str]]:
    """The registered commands whose modules are installed: name -> (module, help)."""
    import importlib.util

    return {k: v for k, v in COMMANDS.items() if importlib.util.find_spec(v[0]) is not None}


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line error (no usage dump): ``inserr <cmd>: error: ...``."""

    def error(self, message: str):  # noqa: D102 - argparse API
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The argument parser; sub-command arguments are added only for ``command``."""
    parser = _Parser(
        prog="inserr",
        description="Error analysis of rotation-modulated strapdown inertial navigation.",
    )
    from inserr import __version__

    parser.add_argument("--version", action="version", version=f"inserr {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name, (module, help_) in available_commands().items():
        p = sub.add_parser(name, help=help_, description=help_)
        if name == command:
            importlib.import_module(module).add_arguments(p)
    return parser


def _options(parser: argparse.ArgumentParser) -> tuple[set[str], set[str]]:
    """Option strings of ``parser`` and its sub-commands: those taking a value, and all."""
    takes: set[str] = set()
    every: set[str] = set()
    for action in parser._actions:  # argparse keeps no public list of its actions
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                t, e = _options(sub)
                takes |= t
                every |= e
        every.update(action.option_strings)
        if action.nargs != 0:
            takes.update(action.option_strings)
    return takes, every


def join_negative_values(argv: list[str], parser: argparse.ArgumentParser) -> list[str]:
    """``--flag -value`` as ``--flag=-value`` for every flag that takes a value.

    argparse takes a word that starts with ``-`` for an option unless it looks like a
    plain negative number, so ``--yaw-swing -6,60`` or ``--duration -3min`` would be
    an argparse error instead of the value's own message. A word after a value-taking
    flag is its value unless it is one of the parser's options (or starts with
    ``--``); a unique abbreviation of a flag counts as the flag, as argparse allows.
    Everything after ``--`` is left alone.
    """
    takes, every = _options(parser)
    out: list[str] = []
    i = 0
    while i < len(argv):
        word = argv[i]
        if word == "--":
            out.extend(argv[i:])
            break
        flag = word
        if word.startswith("--") and word not in every and "=" not in word:
            matches = [o for o in every if o.startswith(word)]
            flag = matches[0] if len(matches) == 1 else word
        nxt = argv[i + 1] if i + 1 < len(argv) else None
        if (
            flag in takes
            and nxt is not None
            and nxt.startswith("-")
            and not nxt.startswith("--")
            and len(nxt) > 1
            and nxt not in every
        ):
            out.append(f"{word}={nxt}")
            i += 2
            continue
        out.append(word)
        i += 1
    return out


def input_files(args: argparse.Namespace) -> list[str]:
    """The files a command reads that are named on its command line (the scenario file)."""
    path = getattr(args, "scenario", None)
    return [path] if path else []


@contextmanager
def _terminate_as_interrupt():
    """Let SIGTERM (``kill PID``) unwind like Ctrl-C, so no partial output is kept.

    Only in the main thread of the process (where Python delivers signals); the
    previous handler is restored afterwards.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


#: Optional packages (top-level import names) -> the extra of inserr that installs them.
OPTIONAL_EXTRAS = {"dask": "sweep", "distributed": "sweep", "pyins": "reference"}


def _missing_extra(command: str, exc: ModuleNotFoundError) -> int:
    """One line naming the ``pip install`` that fixes a missing optional package."""
    top = (exc.name or "").split(".")[0]
    extra = OPTIONAL_EXTRAS.get(top)
    if extra is None:  # not an optional extra: a broken installation, keep the traceback
        raise exc
    print(
        f"inserr {command}: error: needs the optional package {top!r}, which is not installed. "
        f"Fix: pip install 'inserr[{extra}]'",
        file=sys.stderr,
    )
    return 2


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the process exit status (0 ok, 2 bad input, 1 failure)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    command = next((a for a in argv if not a.startswith("-")), None)
    parser = build_parser(command)
    args = parser.parse_args(join_negative_values(argv, parser))
    if args.command is None:
        parser.print_help()
        return 2
    try:
        module = importlib.import_module(COMMANDS[args.command][0])
    except ModuleNotFoundError as exc:
        return _missing_extra(args.command, exc)
    if getattr(args, "json", False):
        from inserr.output.progress import set_quiet

        set_quiet(True)
    try:
        # A report directory is replaced as a whole: refuse a dangerous --out before
        # any work. (A sweep's --out is a resumable store with its own checks.)
        if getattr(args, "out", None) is not None and args.command not in _OWN_OUT_CHECK:
            from inserr.output.report import check_report_dir

            check_report_dir(args.out, "--out", inputs=input_files(args))
        with _terminate_as_interrupt():
            return int(module.run(args) or 0)
    except InputError as exc:
        from inserr.scenario.flags import name_the_flag

        # The library names scenario keys; add the flag where the value came from one.
        print(f"inserr {args.command}: error: {name_the_flag(exc, args)}", file=sys.stderr)
        return 2
    except ModuleNotFoundError as exc:
        return _missing_extra(args.command, exc)
    except KeyboardInterrupt:
        what = {
            "sweep": "finished points are kept; rerun with the same --out to resume",
            "design": "finished evaluations are kept; rerun with the same --out to resume",
        }.get(args.command, "no partial report was kept")
        print(f"inserr {args.command}: interrupted; {what}", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
