"""``inserr imu-budget RECORDING.csv --rate HZ``: IMU noise terms from a static recording.

Example::

    inserr imu-budget static_2h.csv --rate 100 --out noise_report
    inserr imu-budget static_2h.csv --rate 100 --gyro-unit deg/s --accel-unit g --json

The recording is a CSV file: time (s) or sample index, gyro x, y, z, accelerometer x,
y, z, one line per sample, units in a header line (``time (s), gyro x (deg/s), ...``)
or given with ``--gyro-unit`` / ``--accel-unit``. The overlapping Allan deviation of
every axis is fitted with the IEEE Std 952 slopes (:mod:`inserr.calibration.allan`);
the output is a table of the terms with their confidence intervals and a ready
``[imu]`` scenario section (``inserr run`` reads it as it is).
"""

from __future__ import annotations

import argparse

from inserr.cli.common import add_json_flag, emit, format_table


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("recording", help="static recording, CSV: t or sample, 3 gyro, 3 accel")
    p.add_argument("--rate", required=True, metavar="HZ", help="sample rate (Hz)")
    p.add_argument(
        "--gyro-unit", default=None, metavar="UNIT", help="gyro columns: deg/s, rad/s or deg/h"
    )
    p.add_argument(
        "--accel-unit", default=None, metavar="UNIT", help="accelerometer columns: m/s^2, g, mg, ug"
    )
    p.add_argument(
        "--confidence", default="0.95", metavar="P", help="level of the intervals (default 0.95)"
    )
    p.add_argument("--out", default=None, metavar="DIR", help="write a report directory")
    add_json_flag(p)


def run(args: argparse.Namespace) -> int:
    from inserr.calibration.allan import (
        AXES,
        SENSORS,
        TERM_POWERS,
        TERMS,
        check_rate,
        fit_recording,
        in_units,
        read_recording,
        summary,
    )
    from inserr.core.errors import InputError

    rate = check_rate(args.rate, "--rate")
    try:
        confidence = float(args.confidence)
    except ValueError:
        confidence = float("nan")
    if not 0.5 <= confidence < 1.0:
        raise InputError("--confidence", f"expected a level in [0.5, 1), got {args.confidence!r}")
    try:
        rec = read_recording(
            args.recording, rate, gyro_unit=args.gyro_unit, accel_unit=args.accel_unit
        )
    except InputError as exc:
        # The library names its arguments; on the command line they are flags.
        raise InputError(exc.field, *(_flags(t) for t in (exc.problem, exc.fix))) from None
    fit = fit_recording(rec, confidence)
    result = summary(fit)
    if args.out:
        from inserr.calibration.report import build_noise_report

        result["report"] = str(build_noise_report(fit).write(args.out))
    pct = f"{confidence:.0%}"
    lines = [
        f"{rec.source}: {rec.samples} samples at {rate:g} Hz ({rec.duration / 3600:.3g} h); "
        f"Allan deviation fitted with the IEEE slopes, {pct} intervals",
    ]
    for sensor in SENSORS:
        rows = []
        for name in TERM_POWERS:
            label, unit, _ = TERMS[sensor][name]
            row = [f"{label} ({unit})"]
            for axis in AXES:
                t = fit.term(sensor, axis, name)
                lo, val, hi = (in_units(sensor, name, v) for v in (t.low, t.value, t.high))
                row.append(f"{val:.3g} [{lo:.3g}, {hi:.3g}]" if t.resolved else f"< {hi:.3g}")
            rows.append(row)
        lines += ["", format_table([sensor, *AXES], rows)]
    lines += ["", result["imu_section"].rstrip()]
    if args.out:
        lines += ["", f"report written to {result['report']}/report.html"]
    emit(args, result, "\n".join(lines))
    return 0


#: The reader's argument names and the flags that set them.
_ARGUMENT_FLAGS = {"gyro_unit": "--gyro-unit", "accel_unit": "--accel-unit", "(rate": "(--rate"}


def _flags(text: str | None) -> str | None:
    """``text`` with the reader's argument names turned into this command's flags."""
    if text is None:
        return None
    for name, flag in _ARGUMENT_FLAGS.items():
        text = text.replace(name, flag)
    return text
