"""P0 through the nonlinear reference: linear prediction vs full strapdown navigation, 72 h.

For every experiment (scenario file) and every scheme of its ``[compare]`` list, run the
linear drift analysis and the nonlinear reference (python-ins strapdown navigation of
ideal increments from inverse navigation, P0's budget injected in the IMU frame, 100 Hz):
a deterministic run (constant errors as given, no noise) compared with the linear
response, and one noisy realisation (the scenario's seed), as P0 ran it. Then probes of
where the linearisation breaks (:mod:`inserr.reference.linearity`).

    python analyses/p0_swinging_base/nonlinear.py [--jobs N] [--quick] [--fresh [SCHEMES]]

Finished cases are cached in ``out/nonlinear_cache/`` (keyed by the scenario file's
text, the scheme, the duration and the rate; not by the inserr source: after a change
of a scheme or the model, ``--fresh``), so an interrupted run resumes and ``--report``
rewrites ``results/NONLINEAR.md`` from the cache alone. Needs ``pip install 'inserr[reference]'``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np

from inserr.output.report import Report, dumps, write_bytes_atomic, write_text_atomic
from inserr.reference import linearity as lin
from inserr.scenario.schema import load_scenario

HERE = Path(__file__).resolve().parent
SCENARIOS = (HERE / "scenario.toml", HERE / "scenario_exp2.toml")
CACHE = HERE / "out" / "nonlinear_cache"


def _scenario(path: Path, hours: float | None):
    scen = load_scenario(path)
    return scen.with_changes({"scenario.duration": f"{hours} h"}) if hours else scen


def cache_file(path: Path, scheme: str, hours: float | None, rate: float) -> Path:
    """Cache entry of a case: the scenario file's text, scheme, duration and rate."""
    key = hashlib.sha256((path.read_text(encoding="utf-8") + f"|{scheme}|{hours}|{rate}").encode())
    return CACHE / f"{path.stem}__{scheme}__{key.hexdigest()[:16]}.npz"


def run_case(path: Path, scheme: str, hours: float | None, rate: float) -> Path:
    """:func:`~inserr.reference.linearity.linear_and_nonlinear` of one case, cached atomically."""
    out = cache_file(path, scheme, hours, rate)
    if not out.is_file():
        info, arrays = lin.linear_and_nonlinear(_scenario(path, hours), scheme, rate)
        info["scenario_file"] = path.name
        CACHE.mkdir(parents=True, exist_ok=True)
        tmp = out.with_name(f".{out.stem}.{os.getpid()}.tmp.npz")
        np.savez_compressed(tmp, info=json.dumps(info), **arrays)
        os.replace(tmp, out)
    return out


def write_up(result: dict, by_exp: dict) -> Report:
    """NONLINEAR.md: the cases, why they agree, the probes, and what the agreement shows."""
    ok = [c for c in result["cases"] if c.get("status") == "ok"]
    rep = Report("P0 through the nonlinear reference")
    rep.paragraph(
        f"Written by `nonlinear.py`; numbers from `nonlinear.json`. {result['hours']:g} h at "
        f"{result['imu_rate_hz']:g} Hz, headings read {result['heading_convention']}. Linear: "
        "inserr's psi-angle model; nonlinear: python-ins strapdown navigation of ideal increments "
        "(inverse navigation of the exact IMU attitude history) with the same deterministic "
        "errors injected in the IMU frame. Horizontal errors in nmi."
    )
    rep.paragraph(
        "**What the agreement shows.** The nonlinear reference runs the same scenario files, "
        "so it shares their reading of P0's set-up (heading convention, error signs, opening "
        "phase, stop time). It validates the linearization of that reading, not the reading: "
        "whether the reading is P0's is the subject of REPORT.md's 'Against the paper'."
    )
    rep.table(*lin.case_table(result["cases"]))
    if ok:
        worst = max(ok, key=lambda c: c["relative_difference"])
        dr_r = (
            max(c["linear_max_horizontal_error_nmi"] for c in ok)
            * 1852.0
            / result["sizes"]["radius_m"]
        )
        rates = result.get("imu_rate_dependence") or []
        rd = ", ".join(f"{r['relative_difference']:.1e} at {r['imu_rate_hz']:g} Hz" for r in rates)
        rep.paragraph(
            f"Largest relative difference of the maxima {worst['relative_difference']:.1e} "
            f"({worst['scenario_file']}, {worst['scheme']}). Why they agree: P0's errors are "
            "tiny for the linearisation (tilts of seconds of arc, a heading error of minutes, "
            f"centimetres per second, dr / R up to {dr_r:.0e}); every term the linear model drops "
            "is a product of two such errors. The residual mixes those terms with the "
            "reference's own discretisation"
            + (f"; IMU-rate probe (experiment 1, two-position, 1 h): {rd}." if rates else ".")
        )
    probes = result.get("linearity_limits")
    if probes:
        rep.heading("Where the linearisation does break")
        rep.paragraph("Static, P0's site and attitude, 4 h, 2 Hz, one error at a time:")
        rep.table(*lin.probe_table(probes), "{:.3g}")
        limits = lin.probe_limits(probes, result["sizes"])
        share = result["heading_pseudo_drift_check"]["share_explained"]
        rep.paragraph(
            "The difference grows as the square of the error that causes it (the signature of the "
            "dropped second-order terms, not of a convention error, which would be first order). "
            f"The small-angle form of the attitude error explains {100 * share:.0f} % of it at a "
            "3 deg heading error. The linear prediction holds to 1 % (RMS difference over the "
            "maximum) for "
            + "; ".join(
                f"{k} up to {v['text']}" + (f" ({v['ratio']:.0f} x P0's)" if v["ratio"] else "")
                for k, v in limits.items()
            )
            + "; a free vertical channel diverges within an hour or two."
        )
    for k, cases in enumerate(by_exp.values(), start=1):
        title = f"{cases[0][0]['experiment']}: linear (solid) vs nonlinear (dashed)"
        rep.figure(lin.comparison_figure(cases, title), f"nonlinear_exp{k}", title)
    return rep


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--schemes", default=None, help="comma-separated (default: each file's [compare])"
    )
    p.add_argument("--quick", action="store_true", help="1 h runs, written to out/nonlinear_quick/")
    p.add_argument("--rate", type=float, default=100.0, help="IMU sample rate, Hz (P0's 100)")
    p.add_argument("--jobs", type=int, default=1, help="cases run in parallel processes")
    p.add_argument(
        "--fresh",
        nargs="?",
        const="all",
        default=None,
        metavar="SCHEMES",
        help="recompute cached cases: all, or these comma-separated schemes",
    )
    p.add_argument("--no-probes", action="store_true", help="skip the linearity probes (~2 min)")
    p.add_argument("--report", action="store_true", help="only rewrite the outputs from the cache")
    args = p.parse_args(argv)
    from inserr.reference.strapdown import require_pyins

    require_pyins()
    hours = 1.0 if args.quick else None
    todo = []
    for path in SCENARIOS:
        for name in args.schemes.split(",") if args.schemes else load_scenario(path).compare:
            todo.append((path, name))
            if args.fresh == "all" or (args.fresh and name in args.fresh.split(",")):
                cache_file(path, name, hours, args.rate).unlink(missing_ok=True)
    files, failed = {}, []
    if args.report:
        files = {c: f for c in todo if (f := cache_file(*c, hours, args.rate)).is_file()}
        failed = [
            {"scenario_file": c[0].name, "scheme": c[1], "status": "not run (no cached result)"}
            for c in todo
            if c not in files
        ]
    else:
        with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
            futures = {pool.submit(run_case, *c, hours, args.rate): c for c in todo}
            for fut in as_completed(futures):
                path, name = futures[fut]
                try:
                    files[(path, name)] = fut.result()
                    print(f"done {path.name} {name}", file=sys.stderr, flush=True)
                except Exception as exc:  # noqa: BLE001 - keep the other cases
                    failed.append(
                        {"scenario_file": path.name, "scheme": name, "status": f"failed: {exc!r}"}
                    )
    rows, by_exp = [], {}
    for case in todo:
        if case in files:
            with np.load(files[case]) as z:
                d = {k: z[k] for k in z.files}
            info = json.loads(str(d["info"]))
            rows.append(lin.case_row(info))
            by_exp.setdefault(case[0], []).append((info, d))
    scen = load_scenario(SCENARIOS[0])
    result = {
        "hours": 1.0 if args.quick else scen.duration / 3600.0,
        "imu_rate_hz": args.rate,
        "heading_convention": scen.heading_convention,
        "cases": rows + failed,
        "sizes": lin.error_sizes(scen),
    }
    if not args.no_probes:
        base = lin.static_base(scen)
        result["linearity_limits"] = lin.linearity_probes(base)
        result["heading_pseudo_drift_check"] = lin.pseudo_drift_check(base)
        result["imu_rate_dependence"] = lin.rate_dependence(
            scen.with_changes({"scheme.name": "two-position"})
        )
    out = HERE / "out" / "nonlinear_quick" if args.quick else HERE / "results"
    out.mkdir(parents=True, exist_ok=True)
    rep = write_up(result, by_exp)
    write_text_atomic(out / "nonlinear.json", dumps(result) + "\n")
    for name, data in rep.files("NONLINEAR.md").items():
        if name.endswith(".png") or name == "NONLINEAR.md":
            write_bytes_atomic(out / name, data)
    for r in rows:
        print(
            r["scenario_file"], r["scheme"], f"relative difference {r['relative_difference']:.2e}"
        )
    return 0 if not failed else 1


if __name__ == "__main__":
    sys.exit(main())
