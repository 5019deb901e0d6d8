"""Write-up of the alignment scheme comparison (:mod:`inserr.alignment.comparison`).

:func:`build_report` turns the results of
:func:`~inserr.alignment.comparison.compare_schemes` and its figures into a
:class:`~inserr.output.report.Report` for the one writer: set-up, observability, the
filter per scheme, what indexing costs, what the unmodelled errors cost and the
swinging base, every number generated from the results. A sentence whose claim this
run's numbers do not bear out is flagged in the text.
"""

from __future__ import annotations

import math

from inserr.alignment.comparison import NOT, WELL
from inserr.alignment.filter import UNITS
from inserr.alignment.study import SHOWN
from inserr.core.units import MICRO_G
from inserr.output.report import Report


def _f(v, fmt="{:.3g}") -> str:
    return "—" if v is None or (isinstance(v, float) and math.isnan(v)) else fmt.format(v)


def _table(header: list[str], rows: list[list]) -> list[str]:
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return out + [""]


def _states(names: list[str]) -> str:
    return ", ".join(f"`{UNITS[s][0]}`" for s in names) if names else "none"


def _claim(text: str, holds: bool) -> str:
    """A sentence of the write-up, flagged when this run's numbers do not bear it out."""
    return text if holds else text + " **(Not borne out by this run's numbers: see the tables.)**"


def _setup_lines(res: dict) -> list[str]:
    s, fl = res["settings"], res["static_floors"]
    return [
        "## Set-up",
        "",
        f"- Site (P0): latitude {s['lat_deg']:.4g}°, height {s['height_m']:g} m; vehicle "
        f"heading {s['heading_deg']:g}°, pitch {s['pitch_deg']:g}°, roll {s['roll_deg']:g}°.",
        f"- IMU (P0 budget): gyro bias {s['gyro_bias_deg_h']:g} °/h, accelerometer bias "
        f"{s['accel_bias_ug']:g} µg (prior 1σ of the bias states and the true biases of the "
        f"simulated run), ARW {s['arw_deg_rt_h']:g} °/√h, VRW {s['vrw_ug_rt_hz']:g} µg/√Hz; "
        f"scale factors {s['gyro_sf_ppm']:g} / {s['accel_sf_ppm']:g} ppm and misalignments "
        f"{s['gyro_misalignment_arcsec']:g} / {s['accel_misalignment_arcsec']:g}″ (gyro / "
        "accelerometer, all axes) act on the simulated run only: the classic alignment filter "
        "does not model them, so they cannot change any σ below, only the errors of the "
        "simulated run (see *What the unmodelled errors cost*).",
        f"- Alignment {s['minutes']:g} min; zero-velocity updates at {s['zupt_rate_hz']:g} Hz "
        f"with 1σ {s['zupt_sigma_m_s'] * 1e3:g} mm/s on all three axes ({s['vertical']} "
        "vertical channel), no position updates; prior 1σ: tilt "
        f"{s['initial_tilt_arcsec']:g}″, heading {s['initial_heading_arcmin']:g}′, velocity "
        f"{s['initial_velocity_m_s']:g} m/s, position {s['initial_position_m']:g} m. The true "
        "initial errors of the simulated run are the prior 1σ values.",
        f"- Schemes: table {s['rate_deg_s']:g} °/s about the vehicle's up axis, stops of "
        f"{s['stop_s']:g} s. P0's 300 s stops would leave a 10-minute alignment with two stops "
        "of the two-position cycle and only two of the four positions of the four-position "
        "scheme; levelling takes seconds and one stop needs about a minute to show the "
        "Earth-rate signature of heading, so 60 s stops give several positions in 10 minutes "
        "(see the stop-time sweep).",
        f"- Static floors for this budget and prior (table at its zero): φE "
        f"{fl['phi_e_arcsec']:.3g}″, φN {fl['phi_n_arcsec']:.3g}″ (∇/g), heading "
        f"{fl['phi_u_arcmin']:.3g}′ (ε_E/(Ω cos L)), each combined with the attitude prior "
        "as 1/σ² = 1/σ_prior² + 1/floor² (with a diffuse prior: φE "
        f"{res['static_floors_diffuse']['phi_e_arcsec']:.3g}″, heading "
        f"{res['static_floors_diffuse']['phi_u_arcmin']:.3g}′).",
        "",
    ]


def _observability_lines(res: dict, names: list[str]) -> list[str]:
    c, ob = res["classic"], res["observability"]
    lines = [
        "## Why zero-velocity alignment cannot see everything",
        "",
        "With the IMU at rest the only measurement is the velocity error, and it stays zero "
        "for every error state that balances itself: a tilt φN whose gravity leak is "
        "cancelled by ∇E = g·φN, a tilt φE cancelled by ∇N = −g·φE, and a gyro bias "
        "ε = −Ω×φ that exactly holds the attitude error still against the Earth rate. The "
        "classic 10-state model (biases in the IMU frame, one segment per heading):",
        "",
    ]
    rows = [
        [label, f"{e['rank']} of {e['n_states']}", "; ".join(e["unobservable"]) or "none"]
        for label, e in (
            ("one heading", c["one_heading"]),
            ("two headings 180° apart", c["two_headings"]),
        )
    ]
    lines += _table(["segments", "rank", "unobservable directions"], rows)
    lines += [
        "The full 15-state model over each scheme's real timeline (stops *and* table turns as "
        "exact constant-rate segments; Goshen-Meskin total observability matrix; ψ is the "
        "model's attitude state, equal to φ at a known position):",
        "",
    ]
    rows = []
    for n in names:
        for key, label in (("zupt", "ZUPT"), ("zupt_position", "ZUPT + position")):
            e = ob[n][key]
            rows.append(
                [
                    n,
                    label,
                    f"{e['rank']} of {e['n_states']}",
                    "; ".join(e["unobservable"]) or "none",
                ]
            )
    lines += _table(["scheme", "measurements", "rank", "unobservable directions"], rows)
    indexed = [n for n in names if n != "none"]
    full_with_pos = all(
        ob[n]["zupt_position"]["rank"] == ob[n]["zupt_position"]["n_states"] for n in indexed
    )
    two_left = all(ob[n]["zupt"]["n_states"] - ob[n]["zupt"]["rank"] == 2 for n in indexed)
    lines += [
        _claim(
            "Without position updates two directions stay unobservable for every indexed "
            "scheme, and neither is about attitude: an east position (longitude) error with "
            "ψ = −δθ (the computed frame slides along a parallel; nothing a resting IMU senses "
            "changes), and a height error traded against the vertical accelerometer bias "
            "(∇U = −(2g/R)·δrU, the gravity gradient; the tilted table axis adds small terms).",
            two_left,
        ),
        _claim(
            "With position updates every indexing scheme makes all 15 states observable in "
            "principle; the filter below shows how much of that a 10-minute alignment turns "
            "into accuracy.",
            full_with_pos,
        ),
        "",
    ]
    return lines


def _filter_lines(res: dict, names: list[str]) -> list[str]:
    st, fl = res["static"], res["static_floors"]
    lines = [
        "## Final 1σ and convergence time (static base)",
        "",
        "Convergence time = first time after which σ stays within 10 % of its final value; "
        "'—' = not estimated (σ fell by less than 10 % of its prior).",
        "",
    ]
    header = ["state"] + [f"{n} σ" for n in names] + [f"{n} t (s)" for n in names]
    rows = []
    for state in SHOWN:
        key = UNITS[state][0]
        rows.append(
            [f"`{key}`"]
            + [_f(st[n]["final_sigma"][key]) for n in names]
            + [_f(st[n]["convergence_time_s"][key], "{:.0f}") for n in names]
        )
    lines += _table(header, rows)
    gz = res["settings"]
    dg_h = 2.0 * gz["g"] / gz["radius_m"] * gz["initial_position_m"] / MICRO_G
    lines += [
        f"The vertical accelerometer bias stops near {dg_h:.2g} µg = (2g/R)·σ_h: a "
        f"{gz['initial_position_m']:g} m height uncertainty is a gravity error the vertical "
        "channel cannot tell from ∇U (the unobservable direction ∇U = −(2g/R)·δrU above); "
        "position updates remove it.",
        "",
        "Degree of observability √P0/√Pk at the end:",
        "",
    ]
    rows = [
        [f"`{UNITS[x][0]}`"] + [_f(st[n]["observability_degree"][UNITS[x][0]]) for n in names]
        for x in SHOWN
    ]
    lines += _table(["state", *names], rows)
    lines += [
        "## Which states each scheme makes observable",
        "",
        "Two different questions. *Separately observable* is structural: the state is "
        "orthogonal to the null space of the stacked observability matrix of the scheme's "
        "timeline (zero-velocity updates, position known — with the position unknown every "
        "attitude and bias picks up a tiny dr/R or Earth-rate-times-dr coupling and nothing is "
        "formally separable). *σ reduction* is what the 10-minute filter achieved from its "
        f"prior: reduced at least {WELL:g}× (strongly), less than "
        f"{(1 - 1 / NOT) * 100:.0f} % (not), or between (partly). A state can be strongly "
        "reduced yet not separately observable — static heading falls from its "
        f"{res['settings']['initial_heading_arcmin']:g}′ prior to the ε_E/(Ω cos L) floor and "
        "stops there, held by the unobservable combination.",
        "",
    ]
    for n in names:
        cl = st[n]["classes"]
        sep = res["observability"][n]["zupt_position"]["separately_observable"]
        yes = [k for k, v in sep.items() if v]
        lines.append(
            f"- **{n}** — separately observable: {_states(yes) if yes else 'none'}; "
            f"σ reduced strongly: {_states(cl['well'])}; partly: {_states(cl['partly'])}; "
            f"not: {_states(cl['not'])}."
        )

    def cls(n, state):
        return next(k for k, v in st[n]["classes"].items() if state in v)

    acc = ("accel_bias_x", "accel_bias_y")
    steps = [n for n in names if n in ("two-position", "four-position")]
    fs = {n: st[n]["final_sigma"] for n in names}
    lines += ["", "Reading the classes against the physics:", ""]
    if "none" in names:
        ok = (
            all(cls("none", a) == "not" for a in acc)
            and fs["none"]["phi_u_arcmin"] >= 0.95 * fl["phi_u_arcmin"]
        )
        lines.append(
            "- "
            + _claim(
                "*Static*: the tilts stop at ∇/g and heading at (or, with noise, above) "
                "ε_E/(Ω cos L), because the horizontal accelerometer biases and the east gyro "
                "bias cannot be told apart from attitude; those biases keep their prior. The "
                "north gyro bias is partly seen (its balance, ε_N = −Ω sin L·φE, is pinned by "
                "the tilt).",
                ok,
            )
        )
    if steps:
        ok = all(cls(n, a) == "well" for n in steps for a in acc) and all(
            fs[n]["phi_u_arcmin"] < fl["phi_u_arcmin"]
            and fs[n]["phi_e_arcsec"] < fl["phi_e_arcsec"]
            for n in steps
        )
        lines.append(
            "- "
            + _claim(
                "*Two- and four-position*: turning the IMU about the (nearly) vertical axis "
                "flips the sign of the horizontal biases in the navigation frame, which breaks "
                "all three balances: the horizontal accelerometer biases become estimable, the "
                "horizontal gyro biases partly, and tilt and heading drop below the static "
                "floors, to a level set by the sensor noise over the run.",
                ok,
            )
        )
    if "continuous" in names:
        ok = (
            all(cls("continuous", a) == "well" for a in acc)
            and cls("continuous", "gyro_bias_x") != "well"
        )
        lines.append(
            "- "
            + _claim(
                "*Continuous rotation*: the horizontal biases are modulated at the table period, "
                "so the accelerometer biases are again estimable; the horizontal gyro biases "
                "average out within each revolution, so they no longer disturb heading — and, "
                "for the same reason, are hardly estimated.",
                ok,
            )
        )
    ok = all(cls(n, "gyro_bias_z") == "not" for n in names)
    lines.append(
        "- "
        + _claim(
            "The gyro bias about the rotation axis (z) is modulated by no single-axis scheme. "
            "The observability matrix still has full rank with position updates (a trace "
            "through the Earth-rate coupling and the tilted table axis), but the signature is "
            "so weak that the filter does not reduce its σ noticeably in the alignment time: "
            "observable is not the same as estimable in the time available.",
            ok,
        )
    )
    lines += [
        "",
        "Least reduced directions of the normalised covariance D0⁻¹PD0⁻¹ (prior-σ units; "
        "eigenvalue 1 = not reduced at all). On the static base the three eigenvalues near 1 "
        "span the unobservable subspace (mostly the horizontal accelerometer biases and the "
        "east gyro bias, whose priors are tighter than their attitude partners'):",
        "",
    ]
    rows = [
        [n, _f(w["eigenvalue"]), w["direction"]] for n in names for w in st[n]["weakest_directions"]
    ]
    lines += _table(["scheme", "eigenvalue", "direction"], rows)
    return lines


def _cost_lines(res: dict, names: list[str]) -> list[str]:
    st = res["static"]
    lines = ["## What indexing costs in time", ""]
    rows = []
    for n in names:
        cc = st[n]["costs"]
        m = cc["heading_sigma_arcmin_at_min"]
        rows.append(
            [
                n,
                cc["stops"],
                f"{cc['turning_fraction'] * 100:.0f} %",
                _f(cc["time_heading_better_than_static_s"], "{:.0f}"),
                _f(cc["time_to_static_heading_floor_s"], "{:.0f}"),
                _f(cc["time_to_accel_xy_10pct_s"], "{:.0f}"),
                _f(m.get("2")),
                _f(m.get("5")),
                _f(m.get("10")),
            ]
        )
    header = [
        "scheme", "stops", "time turning", "t: heading σ below static run (s)",
        "t: heading σ below static floor (s)", "t: ∇x,∇y σ < 10 % (s)",
        "heading σ at 2 min (′)", "5 min (′)", "10 min (′)",
    ]  # fmt: skip
    lines += _table(header, rows)
    indexed = [n for n in names if n != "none"]
    slower_early = "none" in names and all(
        st[n]["costs"]["heading_sigma_arcmin_at_min"].get("2", math.inf)
        >= st["none"]["costs"]["heading_sigma_arcmin_at_min"].get("2", -math.inf)
        for n in indexed
    )
    lines += [
        "Zero-velocity updates continue while the table turns (the IMU sits at the centre "
        "of rotation), so turning time is not dead time. The price of indexing is time to "
        "the second position and beyond: until the IMU has been seen at two headings the "
        "filter cannot separate biases from attitude, and right after the first turn the "
        "heading estimate even loses the static shortcut (a known east gyro bias) because "
        "the turn mixes the gyro biases in the navigation frame.",
        "",
        _claim(
            "At 2 minutes every indexed scheme is still at or above the static heading σ; "
            "the 'below static run' column is the break-even time, after which indexing only "
            "gains.",
            slower_early,
        )
        if indexed
        else "",
        "",
        "Beyond alignment accuracy the cost is hardware: a turntable and motor (and a slip "
        "ring for continuous rotation).",
        "",
        f"### Stop time of the {res['settings']['sweep_scheme']} scheme",
        "",
    ]
    rows = []
    for r in res["stop_sweep"]:
        fs = r["final_sigma"]
        rows.append(
            [
                f"{r['stop_s']:g}",
                r["stops_in_run"],
                f"{r['turning_fraction'] * 100:.0f} %",
                _f(fs["phi_e_arcsec"]),
                _f(fs["phi_u_arcmin"]),
                _f(fs["accel_bias_x_ug"]),
                _f(fs["gyro_bias_x_deg_h"]),
                _f(r["time_to_static_heading_floor_s"], "{:.0f}"),
            ]
        )
    header = [
        "stop (s)", "stops", "turning", "φE σ (″)", "heading σ (′)", "∇x σ (µg)",
        "εx σ (°/h)", "t: heading σ below static floor (s)",
    ]  # fmt: skip
    lines += _table(header, rows)
    sweep = res["stop_sweep"]
    t_floor = [r["time_to_static_heading_floor_s"] for r in sweep]
    eps = [r["final_sigma"]["gyro_bias_x_deg_h"] for r in sweep]
    head = [r["final_sigma"]["phi_u_arcmin"] for r in sweep]
    earlier = all(a <= b for a, b in zip(t_floor, t_floor[1:], strict=False))
    flat = len(head) < 2 or max(head[:-1]) <= 1.1 * min(head[:-1])
    longer = all(a >= b for a, b in zip(eps, eps[1:], strict=False))
    lines += [
        _claim(
            "Short stops reach the static floor sooner (the second position comes earlier).",
            earlier,
        ),
        _claim(
            "The final heading σ hardly depends on the stop time as long as the run holds a "
            "few positions (all but the longest stop within 10 %): it is set by the gyro "
            "noise over the whole run.",
            flat,
        ),
        _claim(
            "The horizontal gyro-bias estimate prefers longer stops (more time per position "
            "for the bias to drift the tilt).",
            longer,
        ),
        "",
    ]
    return lines


def _swing_lines(res: dict) -> list[str]:
    s, sw, fl = res["settings"], res["swing"], res["static_floors"]
    amp = s["swing_amplitude_deg_s"] * s["swing_period_s"] / (2 * math.pi)
    beats = "none" in sw and sw["none"]["final_sigma"]["phi_u_arcmin"] < fl["phi_u_arcmin"]
    lines = [
        "## Swinging base (P0 yaw swing)",
        "",
        f"Heading rate {s['swing_amplitude_deg_s']:g}·cos(2πt/{s['swing_period_s']:g} s) °/s: "
        f"the vehicle itself turns the IMU by about ±{amp:.0f}°, which modulates the "
        "horizontal biases like an indexing scheme does. "
        + _claim("Even the unindexed IMU beats the static heading floor.", beats),
        "",
    ]
    header = ["state"] + [f"{n} σ" for n in sw]
    rows = [
        [f"`{UNITS[x][0]}`"] + [_f(sw[n]["final_sigma"][UNITS[x][0]]) for n in sw] for x in SHOWN
    ]
    return lines + _table(header, rows)


def _unmodelled_lines(res: dict, names: list[str]) -> list[str]:
    """Final attitude errors of the simulated run with and without K = S + M."""
    s = res["settings"]
    keys = ("phi_e_arcsec", "phi_n_arcsec", "phi_u_arcmin")
    rows, kick = [], {}
    for n in names:
        fs = res["static"][n]["final_sigma"]
        with_k = res["static"][n]["final_error"]
        without = res["static_bias_only_error"][n]
        row = [n]
        for k in keys:
            row += [_f(fs[k]), _f(without[k]), _f(with_k[k])]
        rows.append(row)
        kick[n] = max(
            abs(with_k[k] - without[k]) / fs[k] for k in keys
        )  # K's own contribution, in units of sigma
    units = ("″", "″", "′")
    header = ["scheme"]
    for k, u in zip(("φE", "φN", "heading"), units, strict=True):
        header += [f"{k} σ ({u})", f"{k} error, biases only ({u})", f"{k} error, with K ({u})"]
    worst = max(kick, key=kick.get)
    still = [n for n in names if kick[n] < 0.1]
    lines = [
        "## What the unmodelled errors cost",
        "",
        f"The simulated runs carry P0's scale factors ({s['gyro_sf_ppm']:g} ppm) and "
        f"misalignments ({s['gyro_misalignment_arcsec']:g}″); the filter does not. Each table "
        "turn of angle θ about up then kicks the true attitude: a misalignment m coupling the "
        "up rate into a horizontal gyro adds m·∫ω_z about an axis that turns with the table "
        "(2m of tilt for a 180° turn), and the z scale factor adds s_z·θ of heading. The same "
        "runs without those errors (same noise realization) isolate their effect; final "
        "static-base errors of one simulated run:",
        "",
    ]
    lines += _table(header, rows)
    lines += [
        f"Largest effect of the unmodelled errors: **{worst}**, "
        f"{kick[worst]:.2g}σ on its worst attitude component; under 0.1σ: "
        f"{', '.join(still) if still else 'no scheme'}. A scheme that turns during alignment "
        "needs its misalignments calibrated (or modelled) to the level where m·θ is well below "
        "the σ it promises; the σ of the tables above assume exactly that. Even without turns "
        "(`none`) K acts through gravity and Earth rate: an accelerometer misalignment of "
        f"{s['accel_misalignment_arcsec']:g}″ puts g·m on a horizontal axis, "
        f"{s['accel_misalignment_arcsec']:g}″ of apparent tilt that no static alignment can "
        "tell from level.",
        "",
    ]
    return lines


#: The write-up's figures: file stem, caption.
FIGURES = (
    ("sigma_static", "1σ of attitude and IMU-frame biases during alignment, static base."),
    (
        "attitude_error_static",
        "Attitude estimation error of one simulated run per scheme and its ±1σ.",
    ),
    (
        "stop_sweep",
        "Heading and accelerometer-bias σ of the two-position scheme for several stop times.",
    ),
    ("sigma_swing", "1σ on P0's swinging base."),
)


def report_md(res: dict) -> str:
    """The write-up's Markdown sections (set-up to swinging base), generated from ``res``."""
    names = list(res["static"])
    lines = _setup_lines(res)
    lines += _observability_lines(res, names)
    lines += _filter_lines(res, names)
    lines += _cost_lines(res, names)
    lines += _unmodelled_lines(res, names)
    lines += _swing_lines(res)
    return "\n".join(lines)


def build_report(res: dict, figures: dict, source: str) -> Report:
    """The write-up for the one report writer: generated Markdown, figures, ``results.json``.

    Parameters
    ----------
    res : dict
        :func:`~inserr.alignment.comparison.compare_schemes`'s results (written as
        ``results.json``).
    figures : dict
        File stem -> figure, one per entry of :data:`FIGURES`
        (:func:`inserr.alignment.figures.comparison_figures`).
    source : str
        What generated it (e.g. the script and its scenario file), for the first line.
    """
    rep = Report("Alignment observability: static vs indexed fine alignment")
    rep.paragraph(
        f"*Generated by {source}{' (quick run)' if res['quick'] else ''}. Do not edit by hand.*"
    )
    rep.markdown_text(report_md(res))
    for name, caption in FIGURES:
        rep.figure(figures[name], name, caption)
    rep.results = res
    return rep
