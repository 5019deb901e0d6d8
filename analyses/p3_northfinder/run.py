"""P3 north-finder analysis: heading accuracy vs time, table rate, gyro grade, heading x latitude.

Reads ``scenario.toml`` beside this file and writes ``results/`` (figures,
``results.json`` and ``REPORT.md``, every number in the report taken from the
results). ``--quick`` runs a reduced version into ``out/`` (git-ignored). The study is
:func:`inserr.northfinder.accuracy.accuracy_study`, set against P3's published figures
by :func:`inserr.northfinder.published.against_published`; the write-up is
:func:`inserr.northfinder.accuracy_report.build_report`.

    python analyses/p3_northfinder/run.py [--quick] [--scenario FILE] [--out DIR]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from inserr.core.errors import InputError
from inserr.core.units import MIL
from inserr.northfinder.accuracy import AccuracyStudy, accuracy_study
from inserr.northfinder.accuracy_report import build_report
from inserr.northfinder.inputs import northfinder_inputs
from inserr.northfinder.published import PublishedRepeatability, against_published
from inserr.output.report import check_report_dir
from inserr.scenario.schema import Key, load_scenario

HERE = Path(__file__).resolve().parent


#: This study's own tables of scenario.toml, ``[analysis.NAME]``, validated by the schema code.
ANALYSIS = {
    "monte_carlo": {
        "quick_runs": Key("int", None, 30, "runs of every Monte Carlo in --quick"),
        "check_runs": Key("int", None, 1000, "runs of the check at the required grade"),
        "quick_check_runs": Key("int", None, 30, "the same in --quick"),
    },
    "requirement": {
        "heading_1sigma": Key("angle", None, "0.5 mil", "required heading 1 sigma"),
        "time": Key("time", None, "3 min", "in this time"),
    },
    "time_history": {
        "duration": Key("time", None, "10 min", "length of the time history"),
        "quick_duration": Key("time", None, "4 min", "the same in --quick"),
    },
    "rate_sweep": {
        "rates": Key("angular_rate", "list", [], "table rates"),
        "stress_bias_instability": Key("angular_rate", None, "0.05 deg/h", "harsher gyro GM"),
        "stress_correlation_time": Key("time", None, "20 s", "its correlation time"),
    },
    "grade_sweep": {
        "factors": Key("float-list", None, [], "every gyro error scaled by these"),
        "latitudes": Key("angle", "list", [], "at these latitudes"),
    },
    "bias_instability": {
        "correlation_times": Key("time", "list", [], "Gauss-Markov correlation times"),
    },
    "map": {
        "bound_heading_step": Key("angle", None, "15 deg", "bound map: heading step"),
        "bound_latitude_step": Key("angle", None, "5 deg", "bound map: latitude step"),
        "bound_latitude_limit": Key("angle", None, "85 deg", "bound map: largest |latitude|"),
        "quick_bound_heading_step": Key("angle", None, "45 deg", "the same in --quick"),
        "quick_bound_latitude_step": Key("angle", None, "17 deg", "the same in --quick"),
        "mc_headings": Key("angle", "list", [], "Monte Carlo map: headings"),
        "mc_latitudes": Key("angle", "list", [], "Monte Carlo map: latitudes"),
        "mc_runs": Key("int", None, 60, "Monte Carlo map: runs per cell"),
        "quick_mc_headings": Key("angle", "list", [], "the same in --quick"),
        "quick_mc_latitudes": Key("angle", "list", [], "the same in --quick"),
    },
    "paper": {
        "heading_1sigma": Key("angle", None, "0.5 mil", "published heading 1 sigma"),
        "time": Key("time", None, "3 min", "after this time"),
        "latitude_1sigma": Key("angle", None, "0.0538 deg", "published latitude 1 sigma"),
    },
    "small_angle": {
        "gyro_tilts": Key("angle", "list", [], "gyro tilts"),
        "accel_azimuths": Key("angle", "list", [], "accelerometer azimuths"),
        "accel_tilts": Key("angle", "list", [], "accelerometer tilts"),
    },
}


def load(path: Path, quick: bool) -> tuple[AccuracyStudy, PublishedRepeatability]:
    """The scenario file (a north-finder scenario with this study's tables), in SI.

    Parameters
    ----------
    path : Path
        ``scenario.toml`` (every quantity with its unit).
    quick : bool
        Use the ``quick_*`` entries (reduced runs and grids).

    Returns
    -------
    AccuracyStudy
        The study's base case and grids.
    PublishedRepeatability
        P3's published figures.
    """
    scen = load_scenario(path, study="northfinder", analysis=ANALYSIS)
    inp = northfinder_inputs(scen)

    def a(key: str):
        value = scen.value(f"analysis.{key}")
        if isinstance(value, tuple):
            if not value:
                raise InputError(f"analysis.{key}", "must be a non-empty list")
            return tuple(value)
        return value

    q = "quick_" if quick else ""
    study = AccuracyStudy(
        pose=inp.pose,
        # What the user tells the estimator, never derived from the simulated latitude.
        hemisphere=inp.hemisphere,
        instrument=inp.instrument,
        grade=inp.grade,
        runs=a("monte_carlo.quick_runs") if quick else inp.runs,
        check_runs=a(f"monte_carlo.{q}check_runs"),
        seed=inp.seed,
        requirement=a("requirement.heading_1sigma"),
        time=a("requirement.time"),
        history_duration=a(f"time_history.{q}duration"),
        rates=a("rate_sweep.rates"),
        stress_bi=a("rate_sweep.stress_bias_instability"),
        stress_tau=a("rate_sweep.stress_correlation_time"),
        factors=a("grade_sweep.factors"),
        grade_latitudes=a("grade_sweep.latitudes"),
        bi_taus=a("bias_instability.correlation_times"),
        map_heading_step=a(f"map.{q}bound_heading_step"),
        map_lat_step=a(f"map.{q}bound_latitude_step"),
        map_lat_limit=a("map.bound_latitude_limit"),
        mc_headings=a(f"map.{q}mc_headings"),
        mc_latitudes=a(f"map.{q}mc_latitudes"),
        mc_map_runs=a("map.mc_runs") if not quick else a("monte_carlo.quick_runs"),
        gyro_tilts=a("small_angle.gyro_tilts"),
        accel_azimuths=a("small_angle.accel_azimuths"),
        accel_tilts=a("small_angle.accel_tilts"),
    )
    paper = PublishedRepeatability(
        a("paper.heading_1sigma"), a("paper.time"), a("paper.latitude_1sigma")
    )
    return study, paper


def main(argv: list[str] | None = None) -> int:
    """Run every study and write the report directory.

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments (default ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status: 0, or 2 for an invalid scenario file.
    """
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="reduced run into out/")
    ap.add_argument("--scenario", default=str(HERE / "scenario.toml"))
    ap.add_argument("--out", default=None, help="output directory")
    args = ap.parse_args(argv)
    out = Path(args.out) if args.out else HERE / ("out" if args.quick else "results")
    try:
        check_report_dir(out, "--out")  # before any work: never replace a user's directory
    except InputError as exc:
        print(f"run.py: error: {exc}", file=sys.stderr)
        return 2
    try:
        sc, paper = load(Path(args.scenario), args.quick)
    except InputError as exc:
        print(f"run.py: error in {args.scenario}: {exc}", file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    results, history = accuracy_study(sc)
    results["against_paper"] = against_published(sc, results, paper)
    results["quick"] = args.quick
    results["elapsed_s"] = time.perf_counter() - t0
    rep = build_report(sc, results, history, args.quick, results["against_paper"])
    path = rep.write(out, markdown_name="REPORT.md")
    need = results["grade_sweep"]["required"]
    print(
        f"wrote {path} in {results['elapsed_s']:.0f} s; required ARW "
        f"{need['monte_carlo']['arw_deg_sqrt_h']:.3g} deg/sqrt(h) (Monte Carlo; bound: "
        f"{need['crlb']['arw_deg_sqrt_h']:.3g}) for {sc.requirement / MIL:g} mil in "
        f"{sc.time / 60:g} min"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
