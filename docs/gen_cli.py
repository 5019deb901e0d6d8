"""The command-line reference (``docs/cli.md``), generated from the argparse parsers of inserr.

The docs build (``docs/hooks.py``) replaces the marker in ``docs/cli.md`` with
:func:`reference`, so the reference lists exactly the commands, arguments,
defaults and help texts the installed ``inserr`` accepts and cannot drift from
the code. ``python docs/gen_cli.py`` prints it.
"""

from __future__ import annotations

import argparse
import functools

from inserr.cli.main import available_commands, build_parser

#: Width of the usage lines (fixed, so the page does not depend on the terminal).
WIDTH = 90


def _subparser(name: str) -> argparse.ArgumentParser:
    parser = build_parser(name)
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices[name]


def _cell(text: str) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def _value(action: argparse.Action) -> str:
    if action.nargs == 0:
        return ""
    if action.choices:
        return " \\| ".join(f"`{c}`" for c in action.choices)
    metavar = action.metavar or (action.dest.upper() if action.option_strings else action.dest)
    return f"`{metavar}`"


def _default(action: argparse.Action) -> str:
    if action.nargs == 0 or action.default in (None, argparse.SUPPRESS, False):
        return ""
    return f"`{action.default}`"


def command_reference(name: str) -> str:
    """Markdown for one command: description, usage, and a table of its arguments."""
    p = _subparser(name)
    p.formatter_class = functools.partial(argparse.HelpFormatter, width=WIDTH)
    formatter = p._get_formatter()
    lines = [
        f"## `inserr {name}`",
        "",
        p.description or "",
        "",
        "```text",
        p.format_usage().strip(),
        "```",
        "",
        "| argument | value | default | description |",
        "|---|---|---|---|",
    ]
    for action in p._actions:
        if isinstance(action, argparse._HelpAction):
            continue
        names = ", ".join(f"`{o}`" for o in action.option_strings) or f"`{action.dest}`"
        if action.required and action.option_strings:
            names += " (required)"
        if isinstance(action, argparse._AppendAction):
            names += " (repeatable)"
        help_text = formatter._expand_help(action) if action.help else ""
        lines.append(f"| {names} | {_value(action)} | {_default(action)} | {_cell(help_text)} |")
    return "\n".join(lines) + "\n"


def offered_flags() -> dict[str, list[str]]:
    """Flag name (without dashes) -> the commands that offer it, from their parsers."""
    out: dict[str, list[str]] = {}
    for name in available_commands():
        for action in _subparser(name)._actions:
            for option in action.option_strings:
                out.setdefault(option.removeprefix("--"), []).append(name)
    return out


def flag_table() -> str:
    """Markdown table of :data:`inserr.scenario.flags.FLAGS`: key, unit, help, commands."""
    from inserr.core.units import UNITS
    from inserr.scenario.flags import FLAGS

    offered = offered_flags()
    lines = [
        "## Flag table",
        "",
        "Every value flag of every command, the scenario key it overrides and its unit for "
        "bare numbers (the default is the key's, per study: see each command below).",
        "",
        "| flag | scenario key | unit | what | commands |",
        "|---|---|---|---|---|",
    ]
    for name, flag in FLAGS.items():
        keys = ", ".join(f"`{k}`" for k in flag.keys)
        commands = ", ".join(offered.get(name, []))
        unit = flag.unit or ("written with the value" if flag.spec.kind in UNITS else "")
        lines.append(f"| `--{name}` | {keys} | {_cell(unit)} | {_cell(flag.help)} | {commands} |")
    return "\n".join(lines) + "\n"


def reference() -> str:
    """Markdown reference of every available ``inserr`` command, after the flag table."""
    commands = available_commands()
    index = ["| command | what it does |", "|---|---|"]
    index += [f"| [`inserr {n}`](#inserr-{n}) | {_cell(h)} |" for n, (_, h) in commands.items()]
    return (
        "\n".join(index)
        + "\n\n"
        + flag_table()
        + "\n"
        + "\n".join(command_reference(n) for n in commands)
    )


if __name__ == "__main__":
    print(reference())
