"""``inserr calibrate``: the ``positioning_sensitivity`` block (issue #6, Deliver 2).

The JSON sensitivities are checked against central finite differences computed here
from scratch: perturb one stop's attitude (about an ENU axis, or one gimbal angle),
simulate the noise-free dwell averages of a sensor with P1's true errors, and re-solve
by least squares with a design matrix written out in this file.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from inserr.calibration.estimation import PARAMETER_NAMES, p1_truth
from inserr.calibration.two_axis_table import builtin_set
from inserr.cli.main import main
from inserr.core.earth import OMEGA_IE, gravity

LAT = math.radians(34.0)  # the CLI default
EPS = np.finfo(float).eps
ARCSEC = math.radians(1.0 / 3600.0)
# SI value of one engineering unit, written out independently of inserr.core.units.
UNIT_SI = {
    "ppm/arcsec": 1e-6 / ARCSEC,
    "arcsec/arcsec": 1.0,
    "(deg/h)/arcsec": math.radians(1.0) / 3600.0 / ARCSEC,
    "ug/arcsec": 9.80665e-6 / ARCSEC,
}
REFERENCE = {
    "gyro": np.array([0.0, OMEGA_IE * math.cos(LAT), OMEGA_IE * math.sin(LAT)]),
    "accel": np.array([0.0, 0.0, gravity(LAT)]),
}
ENU = ("east", "north", "up")
# (sensor axis, input axis) of mis_xy, mis_xz, mis_yx, mis_yz, mis_zx, mis_zy.
MIS = ((0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1))


def cli_json(capsys, *argv):
    assert main(["calibrate", *argv, "--runs", "2", "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def truth(sensor):
    """P1's true parameters (the CLI's truth): K (3x3) and b (3,), SI."""
    imu = p1_truth()
    sf = np.broadcast_to(getattr(imu, f"{sensor}_scale_factor"), 3)
    mis = np.broadcast_to(getattr(imu, f"{sensor}_misalignment"), 6)
    k = np.diag(sf).astype(float)
    for (i, j), m in zip(MIS, mis, strict=True):
        k[i, j] = m
    return k, np.asarray(getattr(imu, f"{sensor}_bias"), float)


def design(inputs):
    """(3N, 12): row (p, i) has u_i under sf_i, u_j under mis_ij, 1 under bias_i."""
    h = np.zeros((len(inputs), 3, 12))
    for i in range(3):
        h[:, i, i] = inputs[:, i]
        h[:, i, 9 + i] = 1.0
    for c, (i, j) in enumerate(MIS):
        h[:, i, 3 + c] = inputs[:, j]
    return h.reshape(-1, 12)


def solve(attitudes_true, attitudes_nominal, dwell, ref, k, b):
    """Noise-free dwell averages at the true attitudes, solved assuming the nominal ones."""
    u_true = np.einsum("pji,j->pi", attitudes_true, ref)
    u_nom = np.einsum("pji,j->pi", attitudes_nominal, ref)
    y = (u_true @ (np.eye(3) + k).T + b - u_nom).ravel()
    w = np.repeat(np.sqrt(dwell), 3)  # white noise q^2 / T per stop
    theta, *_ = np.linalg.lstsq(design(u_nom) * w[:, None], y * w, rcond=None)
    return theta


def perturbed(pset, p, axis, angle):
    """Attitudes with stop p turned by ``angle`` about ``axis`` (ENU name or gimbal)."""
    att = pset.attitudes.copy()
    pos = pset.positions[p]
    if axis in ENU:
        att[p] = Rotation.from_rotvec(angle * np.eye(3)[ENU.index(axis)]).as_matrix() @ att[p]
    elif axis == "outer_gimbal":
        att[p] = pset.table.attitude(pos.outer + angle, pos.inner)
    else:
        att[p] = pset.table.attitude(pos.outer, pos.inner + angle)
    return att


@pytest.mark.parametrize(
    "method, sensor",
    [
        ("offaxis-four-position", "gyro"),
        ("six-position", "gyro"),
        ("six-position", "accel"),
    ],
)
def test_json_sensitivity_matches_finite_differences(capsys, method, sensor):
    out = cli_json(capsys, "--method", method)
    block = (out if sensor == "gyro" else out["accel"])["positioning_sensitivity"]
    pset = builtin_set(method)  # the CLI defaults: 300 s dwell, 6 deg/s
    assert [p["name"] for p in out["positions"]] == [p.name for p in pset.positions]
    ref = REFERENCE[sensor]
    k, b = truth(sensor)
    nominal = pset.attitudes
    # Rows of the estimator (theta_hat = E y), for the tolerance below.
    w = np.repeat(np.sqrt(pset.dwells), 3)
    e_rows = np.linalg.pinv(design(np.einsum("pji,j->pi", nominal, ref)) * w[:, None]) * w
    e_norm = np.linalg.norm(e_rows, axis=1)
    # Tolerance, per parameter j. The JSON is evaluated for an error-free sensor
    # (d theta / d delta = E du/d delta); the data here carry P1's true errors, whose
    # derivative is E (I + K) du/d delta. The difference E K du/d delta is bounded by
    # |E_j| |K|_2 |r|, since |du/d delta| = |C^T (r x a)| <= |r| per rad for a unit axis
    # a. Central differences with h = 1e-6 rad: truncation ~h^2 = 1e-12 relative; the
    # observations are rounded to ~eps |r| per stop, i.e. ~eps |r| / h after dividing
    # by 2h, so 1e-8 |E_j| |r| covers rounding with a margin of ~50. |K|_2 ~ 1.4e-4 for P1.
    h = 1e-6
    k_norm = np.linalg.norm(k, 2)
    tol = e_norm * np.linalg.norm(ref) * (k_norm + 1e-8)
    checked = 0
    for p, pos in enumerate(pset.positions):
        for axis in (*ENU, "outer_gimbal", "inner_gimbal"):
            plus = solve(perturbed(pset, p, axis, h), nominal, pset.dwells, ref, k, b)
            minus = solve(perturbed(pset, p, axis, -h), nominal, pset.dwells, ref, k, b)
            fd = (plus - minus) / (2 * h)  # SI per rad, all 12 parameters
            for j, name in enumerate(PARAMETER_NAMES):
                unit = block[name]["unit"]
                value = block[name]["positions"][pos.name][f"about_{axis}_{_ukey(unit)}"]
                assert abs(value * UNIT_SI[unit] - fd[j]) <= tol[j], (name, pos.name, axis)
                checked += 1
    assert checked == 12 * len(pset) * 5
    # The tolerance is far below the sensitivities it checks, so a wrong sign, axis,
    # position or unit fails. (Accelerometer scale factors have no first-order
    # sensitivity: tilting an axis changes g along it by cos(delta) - 1.)
    for j, name in enumerate(PARAMETER_NAMES):
        unit = block[name]["unit"]
        largest = block[name]["largest"][f"abs_{_ukey(unit)}"] * UNIT_SI[unit]
        assert tol[j] < 2e-3 * largest or (sensor == "accel" and name.startswith("sf_"))


def test_largest_and_unidentifiable(capsys):
    out = cli_json(capsys, "--method", "offaxis-four-position")
    sf_z = out["positioning_sensitivity"]["sf_z"]
    assert sf_z["unit"] == "ppm/arcsec"
    # Every stop of P1's set sees sf_z through the same east tilt (z input W_U cos):
    # the largest entry is a four-way tie about east.
    assert [a["position"] for a in sf_z["largest"]["at"]] == ["p1", "p2", "p3", "p4"]
    assert {a["axis"] for a in sf_z["largest"]["at"]} == {"about_east"}
    top = sf_z["largest"]["abs_ppm_per_arcsec"]
    assert all(
        abs(v["about_east_ppm_per_arcsec"]) == pytest.approx(top, rel=1e-9)
        for v in sf_z["positions"].values()
    )
    assert out["positioning_sensitivity"]["bias_x"]["unit"] == "(deg/h)/arcsec"
    # Four stops with z vertical cannot calibrate the accelerometer x, y inputs: no numbers.
    acc = out["accel"]["positioning_sensitivity"]
    assert acc["bias_z"]["unit"] == "ug/arcsec"
    for name in out["accel"]["unidentifiable"]:
        assert acc[name]["largest"] == {"abs_" + _ukey(acc[name]["unit"]): None, "at": []}
        assert all(v is None for pos in acc[name]["positions"].values() for v in pos.values())
    gimbal = cli_json(capsys, "--method", "six-position", "--positioning-model", "gimbal")
    axes = {
        a["axis"] for p in gimbal["positioning_sensitivity"].values() for a in p["largest"]["at"]
    }
    assert axes == {"about_outer_gimbal", "about_inner_gimbal"}


def _ukey(label):
    return label.replace("(deg/h)", "deg_h").replace("/", "_per_")


def test_human_output_and_report_show_the_sensitivity(capsys, tmp_path):
    out_dir = tmp_path / "rep"
    argv = ["calibrate", "--method", "six-position", "--runs", "3", "--out", str(out_dir)]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "largest first-order sensitivity" in text and "(deg/h)/arcsec" in text
    assert any(line.split()[:2] == ["sf_x", "ppm/arcsec"] for line in text.splitlines())
    md = (out_dir / "report.md").read_text()
    assert "| parameter | unit | p1 E / N / U |" in md and "| max abs | at |" in md
    results = json.loads((out_dir / "results.json").read_text())
    assert set(results["positioning_sensitivity"]) == set(PARAMETER_NAMES)
