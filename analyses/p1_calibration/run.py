"""P1 reproduction: off-axis four-position vs static six-position gyro calibration.

Usage::

    python analyses/p1_calibration/run.py            # full study (~25 s)
    python analyses/p1_calibration/run.py --quick    # fewer runs and sweep points (~5 s)

Reads ``scenario.toml`` next to this file and writes ``results/`` next to it (replaced
atomically): ``REPORT.md`` and ``report.html`` (every number generated from the
results), ``results.json`` and the figures. The study is
:func:`inserr.calibration.comparison.compare_sets`, set against P1's Table 1 by
:func:`inserr.calibration.published.against_published`; the write-up is
:func:`inserr.calibration.comparison_report.build_report`.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

from inserr.calibration.comparison import ComparisonSettings, compare_sets, settings_summary
from inserr.calibration.comparison_report import build_report
from inserr.calibration.inputs import calibration_inputs
from inserr.calibration.published import against_published, published_table
from inserr.calibration.two_axis_table import BUILTIN_SETS, builtin_set, load_position_set
from inserr.core.errors import InputError
from inserr.output.report import check_report_dir
from inserr.scenario.schema import Key, Scenario, load_scenario

HERE = Path(__file__).resolve().parent

#: This study's own tables of scenario.toml, ``[analysis.NAME]``, validated by the schema code.
ANALYSIS = {
    "methods": {
        "sets": Key("list", None, ["offaxis-four-position", "six-position"], "the two sets"),
    },
    "sweeps": {
        "dwell": Key("time", "list", [], "dwell per position"),
        "arw": Key("arw", "list", [], "gyro angle random walk"),
        "positioning_error": Key("angle", "list", [], "positioning-error half-width"),
    },
    "verdict": {"tolerance": Key("float", None, 0.10, "relative sigma difference 'the same'")},
    "paper": {
        "rows": Key("list", None, [], "parameter of each printed row"),
        "candidate_means": Key("float-list", None, [], "printed means, first set"),
        "reference_means": Key("float-list", None, [], "printed means, second set"),
        "scale_factor_unit": Key("float", None, 1.0, "printed unit of the scale factors"),
        "misalignment_unit": Key("angle", None, "1 rad", "printed unit of the misalignments"),
        "bias_unit": Key("angular_rate", None, "1 deg/h", "printed unit of the biases"),
        "runs": Key("int", None, 100, "runs behind each printed mean"),
        "misprint": Key("str", None, "", "first set's parameter printed wrongly"),
        "misprint_reading": Key("float", None, 0.0, "its reading, printed unit"),
        "better_count": Key("int", None, 0, "claimed: first set better on this many"),
        "time_saving": Key("float", None, 0.0, "claimed time saving"),
        "deviation_level": Key("float", None, 0.0, "claimed level of the mean deviations"),
    },
}


def load(path: Path) -> Scenario:
    """The scenario file (a calibration scenario with this study's tables), validated."""
    return load_scenario(path, study="calibration", analysis=ANALYSIS)


def method_set(name: str, dwell: float, rate: float):
    """A built-in set, or a TOML position-set file relative to this directory."""
    if name in BUILTIN_SETS:
        return builtin_set(name, dwell, rate)
    return load_position_set(HERE / name, dwell, rate, field_name="analysis.methods.sets")


def run_study(scen: Scenario, quick: bool):
    """Run the comparison and the check against P1; return the write-up and its numbers."""
    inp = calibration_inputs(scen)
    site, imu, dwell, rate = inp.site, inp.truth, inp.dwell, inp.rate
    config = replace(inp.config, runs=30 if quick else inp.config.runs)
    names = tuple(scen.value("analysis.methods.sets"))
    if len(names) != 2:
        raise InputError(
            "analysis.methods.sets", "give exactly two sets: the four- and the six-position"
        )
    step = 2 if quick else 1
    sweeps = {k: tuple(scen.value(f"analysis.sweeps.{k}"))[::step] for k in ANALYSIS["sweeps"]}
    tol = scen.value("analysis.verdict.tolerance")
    settings = ComparisonSettings(
        tolerance=tol,
        dwells=sweeps["dwell"],
        arws=sweeps["arw"],
        positioning_errors=sweeps["positioning_error"],
        per_sample_check=not quick,
        design_sizes=(4, 6) if quick else (4, 5, 6),
    )

    def make(n: str, d: float):
        return method_set(n, d, rate)

    comparison = compare_sets(names, make, dwell, rate, site, imu, config, settings)
    results = {
        "scenario": settings_summary(site, imu, dwell, rate, config, tolerance=tol, quick=quick),
        **comparison.results,
    }
    p = "analysis.paper."
    misprint = scen.value(p + "misprint")
    paper = published_table(
        names,
        scen.value(p + "rows"),
        (scen.value(p + "candidate_means"), scen.value(p + "reference_means")),
        {k: scen.value(f"{p}{k}_unit") for k in ("scale_factor", "misalignment", "bias")},
        runs=scen.value(p + "runs"),
        misprint=(misprint, scen.value(p + "misprint_reading")) if misprint else None,
        better_count=scen.value(p + "better_count"),
        time_saving=scen.value(p + "time_saving"),
        deviation_level=scen.value(p + "deviation_level"),
        field="analysis.paper",
    )
    sets = {n: make(n, dwell) for n in names}
    results["against_paper"] = against_published(
        comparison, paper, sets, site, imu, config, sweeps["dwell"]
    )
    title = "P1: off-axis four-position vs six-position calibration"
    rep = build_report(comparison, results, title, results["against_paper"], paper="P1")
    return rep, results


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer runs and sweep points")
    parser.add_argument("--scenario", default=str(HERE / "scenario.toml"), help="scenario file")
    parser.add_argument("--out", default=str(HERE / "results"), help="output directory")
    args = parser.parse_args(argv)
    try:
        check_report_dir(args.out, "--out")  # before any work: never replace a user's directory
        rep, results = run_study(load(Path(args.scenario)), args.quick)
    except InputError as exc:
        print(f"run.py: error: {exc}", file=sys.stderr)
        return 2
    out = rep.write(Path(args.out), markdown_name="REPORT.md")
    v = results["verdict"]
    print(f"wrote {out}")
    print(
        f"time saving {100 * v['time_saving']:.1f} %; equal-dwell sigma ratio four/six "
        f"{v['equal_dwell']['min_ratio']:.2f}..{v['equal_dwell']['max_ratio']:.2f}; "
        f"equal-time {v['equal_time']['min_ratio']:.2f}..{v['equal_time']['max_ratio']:.2f}; "
        f"noise-free {v['noise_free']['min_ratio']:.2f}..{v['noise_free']['max_ratio']:.2f}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
