"""``inserr observability``: piecewise-constant observability of zero-velocity alignment.

Two ways to give the segments:

* ``--headings H1,H2,...``: one stop of ``--dwell`` seconds per heading of a level IMU
  turned about the vertical (instantaneous turns). ``--model alignment10`` (default)
  is the classic 10-state model; ``--model full`` the core 15-state model.
* ``--scheme NAME``: the intervals of an indexing scheme running for ``--minutes`` on
  the given base (stops and table turns, or a yaw-swinging base); always the full model.
"""

from __future__ import annotations

import argparse
import math

from inserr.cli.align import add_motion_flags, motion_from_args, quantity_flag
from inserr.cli.common import add_json_flag, emit, format_table, require

MODELS = ("alignment10", "full")


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--lat", default="34", help="latitude, deg (default 34)")
    p.add_argument("--height", default="0", help="height, m")
    p.add_argument(
        "--headings", default=None, help="IMU headings, deg, comma-separated (e.g. 0,180)"
    )
    p.add_argument(
        "--model",
        default=None,
        choices=MODELS,
        help="alignment10 (default with --headings) or full",
    )
    p.add_argument("--dwell", default="60", help="time at each heading, s (default 60)")
    p.add_argument("--position", action="store_true", help="full model: add position measurements")
    p.add_argument(
        "--vertical",
        default="free",
        choices=("free", "clamped"),
        help="full model: vertical channel (free: vertical velocity is measured too)",
    )
    p.add_argument(
        "--scheme", default=None, help="indexing scheme instead of --headings (full model)"
    )
    p.add_argument("--minutes", default="10", help="with --scheme: duration, min (default 10)")
    p.add_argument("--rate", default="6", help="with --scheme: table rate, deg/s (default 6)")
    p.add_argument("--stop", default="60", help="with --scheme: stop time, s (default 60)")
    add_motion_flags(p, "with --scheme: ")
    add_json_flag(p)


def build_system(args: argparse.Namespace):
    """The :class:`~inserr.alignment.observability.Pwcs` the flags describe."""
    import numpy as np

    from inserr.alignment import observability as ob
    from inserr.core.earth import Site
    from inserr.core.errors import InputError

    site = Site(
        quantity_flag(args.lat, "angle", "--lat", "deg"),
        0.0,
        quantity_flag(args.height, "length", "--height", "m"),
    )
    if args.scheme is not None:
        require(args.headings is None, "--headings", "give either --headings or --scheme, not both")
        require(
            args.model in (None, "full"),
            "--model",
            "a scheme timeline needs the full model",
            "use --model full",
        )
        from inserr.alignment.study import Base, alignment_timeline
        from inserr.model.psi_model import ErrorModel, Layout

        motion = motion_from_args(args)
        rate = quantity_flag(args.rate, "angular_rate", "--rate", "deg/s")
        stop = quantity_flag(args.stop, "time", "--stop", "s")
        minutes = quantity_flag(args.minutes, "time", "--minutes", "min")
        require(rate > 0, "--rate", "must be > 0")
        require(stop > 0, "--stop", "must be > 0")
        require(minutes > 0, "--minutes", "must be > 0")
        tl = alignment_timeline(Base(site, motion, rate, stop), args.scheme, minutes)
        model = ErrorModel(site, Layout(bias=True), vertical=args.vertical)
        return ob.full_timeline(model, tl, position=args.position), {"scheme": args.scheme}
    require(
        args.headings is not None,
        "--headings",
        "no segments given",
        "e.g. --headings 0,180 (or --scheme NAME)",
    )
    try:
        hs = [float(v) for v in args.headings.split(",")]
    except ValueError:
        raise InputError(
            "--headings", f"cannot read {args.headings!r}", "comma-separated degrees, e.g. 0,180"
        ) from None
    require(all(math.isfinite(v) for v in hs), "--headings", "headings must be finite")
    dwell = quantity_flag(args.dwell, "time", "--dwell", "s")
    require(dwell > 0, "--dwell", "must be > 0 s")
    h = np.radians(hs)
    extra = {"headings_deg": hs, "dwell_s": dwell}
    if (args.model or "alignment10") == "alignment10":
        require(
            not args.position,
            "--position",
            "the 10-state model has no position states",
            "use --model full",
        )
        return ob.alignment10(site, h, dwell), extra
    return ob.full_headings(site, h, dwell, position=args.position, vertical=args.vertical), extra


def run(args: argparse.Namespace) -> int:
    from inserr.alignment.observability import TYPICAL, analyze

    system, extra = build_system(args)
    res = analyze(system, extra={**extra, "typical_magnitudes_si": dict(TYPICAL)})
    out = res.to_dict()
    s = res.singular_values
    rows = [[i + 1, float(v), float(v / s[0]) if s[0] > 0 else 0.0] for i, v in enumerate(s)]
    human = (
        f"{res.description}\n"
        f"rank {res.rank} of {res.n_states} (tolerance {res.tolerance:.3g}; gap {res.gap:.3g})\n"
        + format_table(["order", "singular value", "relative"], rows)
        + "\n\nunobservable:\n"
        + ("\n".join(f"  {u}" for u in res.unobservable) if res.unobservable else "  none")
    )
    emit(args, out, human)
    return 0
