"""Capture the JSON of every CLI subcommand and every analysis, and compare two captures.

A refactoring or a faster engine must not move any number inserr prints. This script
runs a fixed list of commands (every subcommand with ``--json``, every analysis script
in its quick mode) and stores what each printed or wrote; ``compare`` then holds two
captures side by side, number by number, to a relative tolerance (default 1e-9).

    python tools/golden_outputs.py capture DIR          # run everything, store JSON in DIR
    python tools/golden_outputs.py compare OLD NEW      # exit 1 on any difference
    python tools/golden_outputs.py compare OLD NEW --rtol 1e-6 --only drift-

Keys that only one capture has are listed as differences too (a renamed key is a
change a reviewer must see), except those named in ``--ignore`` (e.g. new metadata).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

QUICKSTART = str(ROOT / "analyses/quickstart/scenario.toml")
P0 = str(ROOT / "analyses/p0_swinging_base/scenario.toml")
#: The P0 file declares counter-clockwise headings since issue 15; the captures before it
#: read it clockwise, so the commands on it say so (the same computation as captured).
P0_CW = ["--heading-convention", "clockwise-from-north"]

#: name -> argument list of ``inserr`` (each prints JSON on stdout)
COMMANDS: dict[str, list[str]] = {
    "modes-34": ["modes", "--lat", "34", "--json"],
    "modes-60-free": ["modes", "--lat", "60", "--vertical", "free", "--json"],
    "drift-static-none": [
        "drift",
        "--scheme",
        "none",
        "--lat",
        "34",
        "--duration",
        "72 h",
        "--gyro-bias",
        "0.02",
        "--accel-bias",
        "100",
        "--json",
    ],
    "drift-static-four-modified": [
        "drift",
        "--scheme",
        "four-position-modified",
        "--duration",
        "24 h",
        "--gyro-bias",
        "0.02",
        "--accel-bias",
        "100",
        "--arw",
        "0.001",
        "--vrw",
        "10",
        "--json",
    ],
    "drift-gm": [
        "drift",
        "--scheme",
        "two-position",
        "--duration",
        "6 h",
        "--gyro-bias",
        "0.01",
        "--gyro-bias-instability",
        "0.005",
        "--accel-bias-instability",
        "20",
        "--gyro-correlation-time",
        "1800",
        "--accel-correlation-time",
        "1800",
        "--json",
    ],
    "drift-swing-two": [
        "drift",
        "--scheme",
        "two-position",
        "--lat",
        "34",
        "--duration",
        "12 h",
        "--gyro-bias",
        "0.02",
        "--accel-bias",
        "100",
        "--gyro-sf",
        "10",
        "--accel-misalignment",
        "10",
        "--yaw-swing",
        "6,120",
        "--pitch",
        "1",
        "--roll",
        "-2",
        "--heading",
        "15",
        "--json",
    ],
    "drift-p0-flexible-6h": [
        "drift",
        P0,
        "--scheme",
        "flexible-two-position",
        "--duration",
        "6 h",
        *P0_CW,
        "--json",
    ],
    "drift-p0-nulling-6h": [
        "drift",
        P0,
        "--scheme",
        "nulling-two-position",
        "--duration",
        "6 h",
        *P0_CW,
        "--json",
    ],
    "drift-p0-isolation-3h": [
        "drift",
        P0,
        "--scheme",
        "heading-isolation",
        "--duration",
        "3 h",
        *P0_CW,
        "--json",
    ],
    "drift-turn-sixteen": [
        "drift",
        "--scheme",
        "sixteen-position",
        "--duration",
        "6 h",
        "--stop",
        "120",
        "--gyro-bias",
        "0.01",
        "--accel-bias",
        "50",
        "--gyro-misalignment",
        "5",
        "--turn-rate",
        "0.5",
        "--json",
    ],
    "drift-continuous": [
        "drift",
        "--scheme",
        "continuous",
        "--reversal",
        "600",
        "--duration",
        "6 h",
        "--gyro-bias",
        "0.01",
        "--accel-bias",
        "50",
        "--gyro-sf",
        "20",
        "--json",
    ],
    "compare-quickstart-6h": ["compare", QUICKSTART, "--duration", "6 h", "--json"],
    "run-quickstart": ["run", QUICKSTART, "--json", "--out", "{tmp}/run-quickstart"],
    "cycle-four": ["cycle", "--scheme", "four-position", "--rate", "6", "--stop", "300", "--json"],
    "cycle-four-modified": ["cycle", "--scheme", "four-position-modified", "--json"],
    "cycle-two": ["cycle", "--scheme", "two-position", "--json"],
    "cycle-eight": ["cycle", "--scheme", "eight-position", "--stop", "120", "--json"],
    "cycle-sixteen": ["cycle", "--scheme", "sixteen-position", "--stop", "120", "--json"],
    "cycle-continuous": ["cycle", "--scheme", "continuous", "--reversal", "600", "--json"],
    "observability-headings": ["observability", "--headings", "0,180", "--json"],
    "observability-scheme": [
        "observability",
        "--scheme",
        "two-position",
        "--duration",
        "10 min",
        "--json",
    ],
    "align-none": ["align", "--json"],
    "align-two": ["align", "--schemes", "none,two-position", "--duration", "6 min", "--json"],
    "calibrate-offaxis": ["calibrate", "--runs", "10", "--json"],
    "calibrate-six": ["calibrate", "--method", "six-position", "--runs", "10", "--json"],
    "calibrate-design": ["calibrate", "--design", "--top", "5", "--json"],
    "northfind": ["northfind", "--lat", "34", "--heading", "30", "--runs", "5", "--json"],
    "northfind-unknown-lat": [
        "northfind",
        "--lat",
        "40",
        "--heading",
        "-100",
        "--runs",
        "5",
        "--duration",
        "2 min",
        "--json",
    ],
    "validate-1h": [
        "validate",
        "--duration",
        "1 h",
        "--gyro-bias",
        "0.02",
        "--accel-bias",
        "100",
        "--scheme",
        "two-position",
        "--json",
    ],
    "sweep-small": [
        "sweep",
        QUICKSTART,
        "--duration",
        "2 h",
        "--param",
        "stop=60,300",
        "--scheme",
        "two-position",
        "--workers",
        "1",
        "--no-plots",
        "--out",
        "{tmp}/sweep-small",
        "--json",
    ],
}

#: name -> (script, its arguments); each writes results.json into --out
ANALYSES: dict[str, tuple[str, list[str]]] = {
    "analysis-alignment": ("analyses/alignment_observability/run.py", ["--quick"]),
    "analysis-p0": ("analyses/p0_swinging_base/run.py", ["--quick"]),
    "analysis-p1": ("analyses/p1_calibration/run.py", ["--quick"]),
    "analysis-p2": ("analyses/p2_four_position/run.py", []),
    "analysis-p3": ("analyses/p3_northfinder/run.py", ["--quick"]),
}


def _run(argv: list[str], cwd: Path) -> subprocess.CompletedProcess:
    # The checkout this script lives in, whatever inserr is installed.
    path = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p)
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONPATH": path}
    return subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True)


#: Commands that take the drift engine's ``--engine`` flag.
DRIFT_FAMILY = ("drift", "compare", "validate", "sweep")  # run reads its file only


def capture(out: Path, only: str = "", engine: str | None = None) -> int:
    """Run every command and analysis; store ``<name>.json`` in ``out``.

    ``engine`` ("exact" or "fast") is passed to the drift-family commands as
    ``--engine`` (the analyses run with the default): with "exact", the step-by-step
    engine of earlier versions answers, so a capture can be held against one made
    before the fast engine existed.
    """
    out.mkdir(parents=True, exist_ok=True)
    failed = 0
    with tempfile.TemporaryDirectory() as tmp:
        for name, args in COMMANDS.items():
            if only and not name.startswith(only):
                continue
            argv = [sys.executable, "-m", "inserr.cli.main", *(a.format(tmp=tmp) for a in args)]
            if engine and args[0] in DRIFT_FAMILY:
                argv += ["--engine", engine]
            proc = _run(argv, Path(tmp))
            if proc.returncode != 0:
                print(f"{name}: exit {proc.returncode}: {proc.stderr.strip()[-400:]}")
                failed += 1
                continue
            (out / f"{name}.json").write_text(proc.stdout, encoding="utf-8")
            print(f"{name}: ok")
        for name, (script, extra) in ANALYSES.items():
            if only and not name.startswith(only):
                continue
            dest = Path(tmp) / name
            proc = _run([sys.executable, str(ROOT / script), *extra, "--out", str(dest)], Path(tmp))
            if proc.returncode != 0:
                print(f"{name}: exit {proc.returncode}: {proc.stderr.strip()[-400:]}")
                failed += 1
                continue
            shutil.copy(dest / "results.json", out / f"{name}.json")
            print(f"{name}: ok")
    return 1 if failed else 0


def _diff(a, b, path: str, rtol: float, atol: float, ignore: set[str], out: list[str]) -> None:
    if path.rsplit(".", 1)[-1] in ignore:
        return
    num = (int, float)
    if isinstance(a, num) and isinstance(b, num) and not isinstance(a, bool):
        if isinstance(b, bool):
            out.append(f"{path}: {a!r} vs {b!r}")
            return
        fa, fb = float(a), float(b)
        if math.isnan(fa) and math.isnan(fb):
            return
        if not math.isclose(fa, fb, rel_tol=rtol, abs_tol=atol):
            out.append(f"{path}: {a!r} vs {b!r}")
        return
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if k in ignore:
                continue
            if k not in a or k not in b:
                out.append(f"{path}.{k}: only in {'new' if k not in a else 'old'}")
                continue
            _diff(a[k], b[k], f"{path}.{k}", rtol, atol, ignore, out)
        return
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            out.append(f"{path}: length {len(a)} vs {len(b)}")
            return
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _diff(x, y, f"{path}[{i}]", rtol, atol, ignore, out)
        return
    if a != b:
        out.append(f"{path}: {a!r} vs {b!r}")


def compare(old: Path, new: Path, rtol: float, atol: float, ignore: set[str], only: str) -> int:
    """Print every difference between two captures; 0 if none."""
    names = sorted({p.stem for p in old.glob("*.json")} | {p.stem for p in new.glob("*.json")})
    bad = 0
    for name in names:
        if only and not name.startswith(only):
            continue
        a, b = old / f"{name}.json", new / f"{name}.json"
        if not a.is_file() or not b.is_file():
            print(f"{name}: only in {'new' if not a.is_file() else 'old'}")
            bad += 1
            continue
        diffs: list[str] = []
        _diff(json.loads(a.read_text()), json.loads(b.read_text()), name, rtol, atol, ignore, diffs)
        if diffs:
            bad += 1
            print(f"{name}: {len(diffs)} difference(s)")
            for d in diffs[:20]:
                print(f"  {d}")
        else:
            print(f"{name}: identical to rtol {rtol:g}")
    return 1 if bad else 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("capture")
    c.add_argument("dir")
    c.add_argument("--only", default="", help="only names starting with this")
    c.add_argument(
        "--engine",
        choices=("fast", "exact"),
        default=None,
        help="drift engine of the drift-family commands (default: theirs)",
    )
    d = sub.add_parser("compare")
    d.add_argument("old")
    d.add_argument("new")
    d.add_argument("--rtol", type=float, default=1e-9)
    d.add_argument("--atol", type=float, default=1e-15, help="absolute floor (round-off)")
    d.add_argument("--ignore", default="", help="comma-separated keys to skip")
    d.add_argument("--only", default="", help="only names starting with this")
    args = ap.parse_args(argv)
    if args.cmd == "capture":
        return capture(Path(args.dir), args.only, args.engine)
    ignore = {k for k in args.ignore.split(",") if k}
    return compare(Path(args.old), Path(args.new), args.rtol, args.atol, ignore, args.only)


if __name__ == "__main__":
    sys.exit(main())
