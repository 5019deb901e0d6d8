"""Mutation testing of inserr's physics core, without the optional extras.

Two modes (``docs/testing.md`` explains both, the scope and the rules):

``python tools/mutation.py --quick``
    Applies a FIXED list of targeted mutations (:data:`QUICK`: sign flips, frame
    transposes C vs C^T, dropped terms, factor changes such as 2 sigma^2/tau -> sigma^2/tau,
    the R_N/R_M swap, RMS as a mean, ...) one at a time as source patches, runs the
    physics test subset (:data:`PHYSICS_TESTS`) with ``-x`` and records killed or
    survived. Under 10 minutes on 2 cores.

``python tools/mutation.py``
    The full mode: every mutant ``mutmut`` (>= 3.8) generates in the physics core
    (``[tool.mutmut]`` in ``pyproject.toml`` plus the function-level scope
    :data:`FULL_SCOPE`), each run against the tests that reach the mutated function.
    Mutants listed in ``tools/mutation_equivalents.toml`` (each with its reason) are
    taken out of the denominator.

Both print ``mutation_score: X`` = killed / (total - documented equivalent mutants).

Environment. The README's test command installs ``.[test]`` only, so the optional
nonlinear reference (``pyins``) is absent and ``tests/test_reference.py`` skips. Every
pytest run here starts with ``sys.modules["pyins"] = None``, which makes ``import
pyins`` fail exactly as if it were not installed (checked before the runs: the harness
stops if pyins can still be imported); nothing is uninstalled.

The working tree is never modified: every mutation is applied to a private copy of
``inserr/``, ``tests/``, ``docs/`` and ``pyproject.toml`` in a temporary directory, which
is removed on any exit (including Ctrl-C, which also ends the running test processes).
"""

from __future__ import annotations

import argparse
import fnmatch
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import tomllib
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EQUIVALENTS = ROOT / "tools" / "mutation_equivalents.toml"

#: What the copy needs: the package, the tests, and the files the tests read.
COPY = ("inserr", "tests", "docs", "pyproject.toml", "mkdocs.yml", "README.md")

#: The physics test subset (rule: every test module of the physics core, i.e. all except
#: those that only exercise the CLI/report/sweep/documentation plumbing or need an
#: optional extra -- test_analyses, test_sweep, test_docs, test_cli, test_calibration_cli,
#: test_calibration_analysis, test_reference -- and except the estimator studies
#: test_alignment, test_observability, test_calibration, whose noise models are tested
#: in test_noise_levels; tests named *cli* are deselected with ``-k "not cli"``). The same
#: rule as ``[tool.mutmut] pytest_add_cli_args_test_selection``. A subset can only kill
#: fewer mutants than the whole suite, so the scores are lower bounds for the README's
#: test command. Ordered fast and targeted first, so that ``-x`` ends a killed run early.
PHYSICS_TESTS = (
    "tests/test_unknown_signs.py",
    "tests/test_paper_comparison.py",
    "tests/test_frames.py",
    "tests/test_fast_propagation.py",
    "tests/test_noise_levels.py",
    "tests/test_scheme_timelines.py",
    "tests/test_scheme_tables.py",
    "tests/test_discretization_paths.py",
    "tests/test_model.py",
    "tests/test_propagate.py",
    "tests/test_rotations.py",
    "tests/test_cycle.py",
    "tests/test_schedule.py",
    "tests/test_nulling.py",
    "tests/test_northfinder.py",
    "tests/test_scenario.py",
)

#: Full mode: mutmut mutates the files of ``[tool.mutmut] only_mutate``; the score counts
#: the mutants of these names (fnmatch patterns of mutmut's mutant names). Whole files
#: for the model, schemes and signs; for the estimators only their noise models.
FULL_SCOPE = (
    "inserr.model.*",
    "inserr.schemes.turntable.*",
    "inserr.schemes.open_loop.*",
    "inserr.schemes.cycle_integrals.*",
    "inserr.schemes.composition.*",
    "inserr.drift.unknown_signs.*",
    "inserr.drift.analysis.*",
    "inserr.alignment.filter.x__noise_factor__mutmut_*",
    "inserr.northfinder.instrument.x__gauss_markov__mutmut_*",
    "inserr.northfinder.instrument.x_simulate__mutmut_*",
    "inserr.northfinder.filter.x_make_filter__mutmut_*",
    "inserr.northfinder.bounds.x_bias_instability_psd__mutmut_*",
    "inserr.northfinder.bounds.x_coefficient_information__mutmut_*",
)

#: Seconds before a quick-mode test run is stopped and counted as killed (a mutant
#: that hangs the suite is detected by the suite); the unmutated subset takes ~35 s.
QUICK_TIMEOUT = 300.0

#: pytest bootstrap: hide pyins (as if not installed), then run pytest.
BOOTSTRAP = (
    "import sys; sys.modules['pyins'] = None; import pytest; sys.exit(pytest.main(sys.argv[1:]))"
)


@dataclass(frozen=True)
class Mutation:
    """One targeted fault: exact source replacements (each ``old`` must occur once)."""

    name: str
    what: str
    edits: tuple[tuple[str, str, str], ...]  # (file, old, new)
    equivalent: str = ""  # reason, if the mutation is known not to change behaviour


def _m(name: str, what: str, *edits: tuple[str, str, str]) -> Mutation:
    return Mutation(name, what, tuple(edits))


PSI = "inserr/model/psi_model.py"
SRC = "inserr/model/error_sources.py"
DISC = "inserr/model/discretization.py"
PROP = "inserr/model/exact_propagation.py"
FAST = "inserr/model/fast_propagation.py"
TL = "inserr/model/timeline.py"
AN = "inserr/drift/analysis.py"
SIGNS = "inserr/drift/unknown_signs.py"
TT = "inserr/schemes/turntable.py"
OL = "inserr/schemes/open_loop.py"
CI = "inserr/schemes/cycle_integrals.py"
COMP = "inserr/schemes/composition.py"
ALF = "inserr/alignment/filter.py"
NFI = "inserr/northfinder/instrument.py"
NFF = "inserr/northfinder/filter.py"
NFB = "inserr/northfinder/bounds.py"

#: The fixed quick list. Names are stable: reports refer to them.
QUICK: tuple[Mutation, ...] = (
    # --- psi model: signs, factors, frames, radii -------------------------------------
    _m(
        "psi-earth-rate-sign",
        "psi' = +Omega x psi (sign flip)",
        (PSI, "f[PSI, PSI] = -skew(om)", "f[PSI, PSI] = skew(om)"),
    ),
    _m(
        "dv-tilt-sign",
        "dv' = -f x psi (sign flip of the tilt coupling)",
        (PSI, "f[DV, PSI] = skew(s.specific_force_n)", "f[DV, PSI] = -skew(s.specific_force_n)"),
    ),
    _m(
        "coriolis-factor",
        "Coriolis -Omega x dv instead of -2 Omega x dv",
        (PSI, "f[DV, DV] = -2.0 * skew(om)", "f[DV, DV] = -1.0 * skew(om)"),
    ),
    _m(
        "radii-swap",
        "R_N and R_M swapped in the Schuler feedback",
        (PSI, "np.diag([-g / s.r_n, -g / s.r_m,", "np.diag([-g / s.r_m, -g / s.r_n,"),
    ),
    _m(
        "gyro-bias-sign",
        "gyro bias drives psi with +I",
        (PSI, 'a[PSI, lay["eps"]] = -np.eye(3)', 'a[PSI, lay["eps"]] = np.eye(3)'),
    ),
    _m(
        "bias-rotation-law",
        "n-resolved biases turn with -w x (python-control path)",
        (PSI, 'a[lay["eps"], lay["eps"]] = rot', 'a[lay["eps"], lay["eps"]] = -rot'),
    ),
    _m(
        "kg-transpose",
        "gyro K^n applied transposed (K^T w) in A",
        (
            PSI,
            'a[PSI, lay["kg"]] = -np.kron(np.eye(3), w_is)',
            'a[PSI, lay["kg"]] = -np.kron(w_is, np.eye(3))',
        ),
    ),
    _m(
        "kg-drop-earth-rate",
        "scale factor/misalignment sees the table rate only",
        (PSI, "w_is = self.site.earth_rate_n + w", "w_is = w"),
    ),
    _m(
        "ka-sign-both-paths",
        "accelerometer K coupling flipped in BOTH code paths",
        (
            PSI,
            'a[DV, lay["ka"]] = np.kron(np.eye(3), self.site.specific_force_n)',
            'a[DV, lay["ka"]] = -np.kron(np.eye(3), self.site.specific_force_n)',
        ),
        (
            PSI,
            'out[:, :, DV, cols("ka")] = dv_mask * kron_rows(f)',
            'out[:, :, DV, cols("ka")] = -dv_mask * kron_rows(f)',
        ),
    ),
    _m(
        "gm-decay-half",
        "gyro GM decays at 1/(2 tau) in A",
        (
            PSI,
            'a[lay["bg"], lay["bg"]] = rot - np.eye(3) / self.gyro_correlation_time',
            'a[lay["bg"], lay["bg"]] = rot - 0.5 * np.eye(3) / self.gyro_correlation_time',
        ),
    ),
    _m(
        "gm-psd-gyro",
        "gyro GM driving PSD sigma^2/tau instead of 2 sigma^2/tau",
        (
            PSI,
            "q[6:9] = 2.0 * gyro_bi**2 / self.gyro_correlation_time",
            "q[6:9] = gyro_bi**2 / self.gyro_correlation_time",
        ),
    ),
    _m(
        "gm-psd-accel",
        "accel GM driving PSD sigma^2/tau instead of 2 sigma^2/tau",
        (
            PSI,
            "q[9:12] = 2.0 * accel_bi**2 / self.accel_correlation_time",
            "q[9:12] = accel_bi**2 / self.accel_correlation_time",
        ),
    ),
    _m("vrw-unsquared", "VRW PSD vrw instead of vrw^2", (PSI, "q[3:6] = vrw**2", "q[3:6] = vrw")),
    _m(
        "exo-gm-decay",
        "structured path: GM decay exp(-2 s/tau)",
        (
            PSI,
            "out[..., sl, sl] = r * np.exp(-s / self.gyro_correlation_time)",
            "out[..., sl, sl] = r * np.exp(-2 * s / self.gyro_correlation_time)",
        ),
    ),
    _m(
        "coupled-eps-transpose",
        "structured path: gyro bias column -R^T instead of -R",
        (
            PSI,
            'out[:, :, PSI, cols("eps")] = -r',
            'out[:, :, PSI, cols("eps")] = -np.swapaxes(r, -1, -2)',
        ),
    ),
    _m(
        "rodrigues-sense",
        "structured path: rotation turned the other way",
        (
            PSI,
            "return np.eye(3) + np.sin(ang) * kx + (1.0 - np.cos(ang)) * (kx @ kx)",
            "return np.eye(3) - np.sin(ang) * kx + (1.0 - np.cos(ang)) * (kx @ kx)",
        ),
    ),
    _m(
        "dtheta-north-radius",
        "position angle: -dr_N / R_N instead of / R_M",
        (PSI, "out[..., 0] = -dr[..., 1] / site.r_m", "out[..., 0] = -dr[..., 1] / site.r_n"),
    ),
    _m(
        "dtheta-up-component",
        "position angle: dr_N tan L instead of dr_E tan L",
        (
            PSI,
            "out[..., 2] = dr[..., 0] * math.tan(site.lat) / site.r_n",
            "out[..., 2] = dr[..., 1] * math.tan(site.lat) / site.r_n",
        ),
    ),
    # --- error sources and the drift analysis ----------------------------------------
    _m(
        "bias-projection-transpose",
        "IMU-frame biases resolved with C^T instead of C",
        (
            SRC,
            'x[lay["eps" if group == "gyro_bias" else "nabla"]] = c_sn0 @ e',
            'x[lay["eps" if group == "gyro_bias" else "nabla"]] = c_sn0.T @ e',
        ),
    ),
    _m(
        "k-projection-transpose",
        "error matrices resolved as C^T K C instead of C K C^T",
        (SRC, "(c_sn0 @ k @ c_sn0.T).reshape(-1)", "(c_sn0.T @ k @ c_sn0).reshape(-1)"),
    ),
    _m(
        "initial-position-psi-sign",
        "initial position error sets psi = +dtheta",
        (
            SRC,
            "x[PSI] = -position_angle(model.site, dr)",
            "x[PSI] = position_angle(model.site, dr)",
        ),
    ),
    _m(
        "drift-starts-from-identity",
        "drift run starts from I instead of C_s^n(0)",
        (
            AN,
            "cols = source_matrix(model, sources, tl.c_sn[0])",
            "cols = source_matrix(model, sources, np.eye(3))",
        ),
    ),
    _m(
        "gm-not-stationary",
        "noise run starts the GM gyro states at zero, not sigma^2",
        (
            AN,
            'p0[nmodel.layout["bg"], nmodel.layout["bg"]] = gbi**2 * np.eye(3)',
            'p0[nmodel.layout["bg"], nmodel.layout["bg"]] = 0.0 * np.eye(3)',
        ),
    ),
    _m(
        "drms-drops-north",
        "noise DRMS from the east variance twice",
        (
            AN,
            "(p[:, 6, 6] + p[:, 7, 7] for p in self.noise_cov.values())",
            "(p[:, 6, 6] + p[:, 6, 6] for p in self.noise_cov.values())",
        ),
    ),
    _m(
        "rms-as-mean",
        "RMS over unknown signs as a mean instead of a root-sum-square",
        (
            SIGNS,
            "np.sqrt(np.sum(np.asarray(vectors) ** 2, axis=(-2, -1)))",
            "np.sqrt(np.mean(np.asarray(vectors) ** 2, axis=(-2, -1)))",
        ),
    ),
    _m(
        "worst-signs-zero",
        "worst case tries signs {0, 1} instead of {-1, +1}",
        (
            SIGNS,
            "(vv[..., 0] == 0) & (vv[..., 1] >= 0)), 1.0, -1.0)",
            "(vv[..., 0] == 0) & (vv[..., 1] >= 0)), 1.0, 0.0)",
        ),
    ),
    # --- the fast engine (inserr.model.fast_propagation, analyze_drift's default) -------
    _m(
        "fast-projection-transpose",
        "fast engine: IMU features from C^T instead of C",
        (FAST, "out[:, :9] = c.reshape(nn, 9)", "out[:, :9] = np.swapaxes(c, 1, 2).reshape(nn, 9)"),
    ),
    _m(
        "fast-gyro-bias-sign",
        "fast engine: gyro bias drives psi with +C e_i",
        (
            FAST,
            "g1 = (y1 * g[None, :, :, None]).sum(axis=2)",
            "g1 = -(y1 * g[None, :, :, None]).sum(axis=2)",
        ),
    ),
    _m(
        "fast-ka-transpose",
        "fast engine: accelerometer error matrix applied transposed",
        (
            FAST,
            "15 + 3 * src.imu_i + src.imu_j]",
            "15 + 3 * src.imu_j + src.imu_i]",
        ),
    ),
    _m(
        "fast-table-transpose",
        "fast engine: table seen through M^T instead of M",
        (
            FAST,
            "out[:, :, :9] = (yy[:, :, :9].reshape(nb, nr * 3, 3) @ m)",
            "out[:, :, :9] = (yy[:, :, :9].reshape(nb, nr * 3, 3) @ np.swapaxes(m, 1, 2))",
        ),
    ),
    _m(
        "fast-vrw-unsquared",
        "fast engine white noise: VRW PSD vrw instead of vrw^2",
        (FAST, "q = np.diag([arw**2] * 3 + [vrw**2] * 3)", "q = np.diag([arw**2] * 3 + [vrw] * 3)"),
    ),
    # --- discretization and propagation ----------------------------------------------
    _m(
        "van-loan-psd-not-sqrt",
        "Van Loan input G Q instead of G sqrt(Q)",
        (
            DISC,
            "g = self.model.noise_input() @ np.sqrt(self.q)",
            "g = self.model.noise_input() @ self.q",
        ),
    ),
    _m(
        "quadrature-weights",
        "structured path: Gauss-Legendre weights doubled",
        (DISC, "wts = 0.5 * h * wts", "wts = h * wts"),
    ),
    _m(
        "quadrature-kernel",
        "structured path: expm(F s) instead of expm(F (h - s))",
        (
            DISC,
            "np.array([expm(f * (h - sj)) for sj in s])",
            "np.array([expm(f * sj) for sj in s])",
        ),
    ),
    _m(
        "covariance-transpose",
        "P <- Phi^T P Phi + Qd",
        (PROP, "p = phi @ p @ phi.T + qd", "p = phi.T @ p @ phi + qd"),
    ),
    _m(
        "powers-dropped",
        "stacked powers Phi^k replaced by Phi",
        (PROP, "new[i] = phi @ new[i - 1]", "new[i] = new[i - 1]"),
    ),
    _m(
        "step-rate-at-end",
        "a step takes the rate of the interval at its end",
        (PROP, "mid = 0.5 * (nodes[:-1] + nodes[1:])", "mid = nodes[1:]"),
    ),
    _m(
        "attitude-at-transpose",
        "attitude along an interval turned the other way",
        (TL, "return rot @ self.c_sn[k]", "return rot.swapaxes(-1, -2) @ self.c_sn[k]"),
    ),
    # --- schemes -----------------------------------------------------------------------
    _m(
        "gimbal-order",
        "C_s^b = rot_x(b) rot_z(a) instead of rot_z(a) rot_x(b)",
        (TT, "c = rot_z(a) @ rot_x(b)", "c = rot_x(b) @ rot_z(a)"),
    ),
    _m(
        "inner-axis-sense",
        "inner gimbal axis rot_z(-a) e_x",
        (
            TT,
            "return np.array([math.cos(a), math.sin(a), 0.0])",
            "return np.array([math.cos(a), -math.sin(a), 0.0])",
        ),
    ),
    _m(
        "modified-four-position-extra",
        "P2's extra stop 1/rate instead of 2/rate",
        (OL, "extra = 2.0 / rate if modified else 0.0", "extra = 1.0 / rate if modified else 0.0"),
    ),
    _m(
        "two-position-no-reversal",
        "two-position cycle turns +180 instead of -180 back",
        (OL, 'Step("outer", -pi, stop, label="0")', 'Step("outer", pi, stop, label="0")'),
    ),
    _m(
        "cycle-antiderivative-transpose",
        "F_z antiderivative of rot_z^T",
        (
            CI,
            "return np.array([[s, c, 0.0], [-c, s, 0.0], [0.0, 0.0, x]])",
            "return np.array([[s, -c, 0.0], [c, s, 0.0], [0.0, 0.0, x]])",
        ),
    ),
    _m(
        "cycle-double-integral-sign",
        "second integral of a turn: + F0 t / r",
        (
            CI,
            "double = left @ ((g1 - g0) / r**2 - f0 * t_turn / r) @ right",
            "double = left @ ((g1 - g0) / r**2 + f0 * t_turn / r) @ right",
        ),
    ),
    _m(
        "table-rate-sign",
        "table turn adds -C_b^n axis rate",
        (COMP, "w_bs_n = c_bn @ axis_b * table.rate[k]", "w_bs_n = -c_bn @ axis_b * table.rate[k]"),
    ),
    _m(
        "substep-rate-frame",
        "sub-step rate from C0^T C1 (IMU frame) instead of C1 C0^T",
        (
            COMP,
            "rel = c_sn[idx + 1] @ np.swapaxes(c_sn[idx], -1, -2)",
            "rel = np.swapaxes(c_sn[idx], -1, -2) @ c_sn[idx + 1]",
        ),
    ),
    # --- estimators' noise models -------------------------------------------------------
    _m(
        "alignment-noise-factor",
        "alignment truth noise scaled by Qd eigenvalues, not sqrt",
        (
            ALF,
            "return v * np.sqrt(np.clip(w, 0.0, None))[None, :]",
            "return v * np.clip(w, 0.0, None)[None, :]",
        ),
    ),
    _m(
        "alignment-measurement-noise",
        "alignment measurement noise R instead of sqrt(R)",
        (
            ALF,
            "z = h @ x_true[:n] + np.sqrt(r_diag) * rng.standard_normal(h.shape[0])",
            "z = h @ x_true[:n] + r_diag * rng.standard_normal(h.shape[0])",
        ),
    ),
    _m(
        "nf-filter-gm-psd",
        "north-finder filter: GM random walk sigma^2/tau per second",
        (
            NFF,
            "q[4] = 2.0 * grade.gyro_bias_instability**2 / grade.gyro_correlation_time * period",
            "q[4] = grade.gyro_bias_instability**2 / grade.gyro_correlation_time * period",
        ),
    ),
    _m(
        "nf-filter-r-period",
        "north-finder filter: R = PSD x T instead of PSD / T",
        (
            NFF,
            "kf.R = np.diag([grade.gyro_arw**2, grade.accel_vrw**2]) / period",
            "kf.R = np.diag([grade.gyro_arw**2, grade.accel_vrw**2]) * period",
        ),
    ),
    _m(
        "nf-gm-start",
        "north-finder GM simulation starts at zero (not stationary)",
        (NFI, "x[:, 0] = sigma * drive[:, 0]", "x[:, 0] = 0.0 * drive[:, 0]"),
    ),
    _m(
        "nf-gm-drive",
        "north-finder GM drive sigma sqrt(1 - a) instead of sqrt(1 - a^2)",
        (
            NFI,
            "x = drive * (sigma * math.sqrt(1.0 - a * a))",
            "x = drive * (sigma * math.sqrt(1.0 - a))",
        ),
    ),
    _m(
        "nf-arw-per-sample",
        "north-finder white noise ARW h instead of ARW sqrt(h)",
        (NFI, "grade.gyro_arw * math.sqrt(h) * noise[0]", "grade.gyro_arw * h * noise[0]"),
    ),
    _m(
        "nf-bound-gm-psd",
        "bias-instability bound with GM PSD sigma^2 tau/(...)",
        (
            NFB,
            "return 2.0 * sigma**2 * tau / (1.0 + (omega * tau) ** 2)",
            "return sigma**2 * tau / (1.0 + (omega * tau) ** 2)",
        ),
    ),
    _m(
        "nf-bound-arw-unsquared",
        "Cramer-Rao information with ARW instead of ARW^2",
        (
            NFB,
            "(([0, 1, 4], grade.gyro_arw**2), ([2, 3, 5], grade.accel_vrw**2))",
            "(([0, 1, 4], grade.gyro_arw), ([2, 3, 5], grade.accel_vrw**2))",
        ),
    ),
)


# --- process handling: nothing outlives the harness, the tree is never touched ------------

_RUNNING: set[subprocess.Popen] = set()
_LOCK = threading.Lock()


def _run(cmd: list[str], cwd: Path, timeout: float | None = None, **kw) -> tuple[int, str, float]:
    """Run ``cmd`` in its own process group; returns (code, output, seconds); -9 on timeout."""
    env = dict(os.environ, PYTHONPATH=str(cwd), PYTHONDONTWRITEBYTECODE="1")
    t0 = time.monotonic()
    proc = subprocess.Popen(
        cmd,
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
        **kw,
    )
    with _LOCK:
        _RUNNING.add(proc)
    try:
        out, _ = proc.communicate(timeout=timeout)
        code = proc.returncode
    except subprocess.TimeoutExpired:
        _kill(proc)
        out, code = proc.communicate()[0] or "", -9
    finally:
        with _LOCK:
            _RUNNING.discard(proc)
    return code, out, time.monotonic() - t0


def _kill(proc: subprocess.Popen) -> None:
    try:
        os.killpg(proc.pid, signal.SIGKILL)  # the group this harness started, by its id
    except ProcessLookupError:
        pass


def _kill_all() -> None:
    with _LOCK:
        procs = list(_RUNNING)
    for p in procs:
        _kill(p)


def _make_copy(parent: Path, name: str) -> Path:
    dest = parent / name
    dest.mkdir()
    for item in COPY:
        src = ROOT / item
        if src.is_dir():
            shutil.copytree(src, dest / item, ignore=shutil.ignore_patterns("__pycache__"))
        elif src.exists():
            shutil.copy2(src, dest / item)
    return dest


def _check_no_pyins(copy: Path) -> None:
    code, out, _ = _run(
        [
            sys.executable,
            "-c",
            "import sys; sys.modules['pyins'] = None\n"
            "try:\n    import pyins\nexcept ImportError:\n    print('pyins hidden')\n"
            "else:\n    print('pyins importable'); sys.exit(1)",
        ],
        copy,
    )
    if code != 0 or "pyins hidden" not in out:
        sys.exit("mutation: could not hide pyins; the runs would not match the README's command")
    print("environment: import pyins fails in every test run (as after pip install '.[test]')")


def _pytest(copy: Path, tests, timeout: float | None, extra=()) -> tuple[int, str, float]:
    args = [sys.executable, "-c", BOOTSTRAP, "-q", "-x", "-p", "no:cacheprovider", "-k", "not cli"]
    args += [*extra, *tests]
    return _run(args, copy, timeout)


# --- quick mode --------------------------------------------------------------------------


def _apply(copy: Path, m: Mutation) -> dict[Path, str]:
    """Apply the edits of ``m`` in ``copy``; returns the original texts to restore."""
    saved: dict[Path, str] = {}
    for file, old, new in m.edits:
        path = copy / file
        text = saved.get(path) or path.read_text()
        saved.setdefault(path, text)
        current = path.read_text()
        if current.count(old) != 1:
            raise RuntimeError(f"{m.name}: {old!r} occurs {current.count(old)} times in {file}")
        path.write_text(current.replace(old, new))
    return saved


def check_quick_list() -> list[str]:
    """Every edit's ``old`` text occurs exactly once in the current sources (stale entries)."""
    problems = []
    names = set()
    for m in QUICK:
        if m.name in names:
            problems.append(f"{m.name}: duplicate name")
        names.add(m.name)
        texts: dict[str, str] = {}
        for file, old, new in m.edits:
            text = texts.setdefault(file, (ROOT / file).read_text())
            if text.count(old) != 1:
                problems.append(f"{m.name}: {old!r} occurs {text.count(old)} times in {file}")
            elif old == new:
                problems.append(f"{m.name}: the edit changes nothing")
            texts[file] = text.replace(old, new)
    return problems


def quick(jobs: int, only: list[str]) -> float:
    stale = check_quick_list()
    if stale:
        sys.exit("mutation: the quick list no longer matches the sources:\n  " + "\n  ".join(stale))
    chosen = [m for m in QUICK if not only or any(fnmatch.fnmatch(m.name, p) for p in only)]
    print(f"quick mode: {len(chosen)} targeted mutations, {jobs} worker(s), tests: physics subset")
    work = Path(tempfile.mkdtemp(prefix="inserr-mutation-"))
    results: dict[str, tuple[str, float]] = {}
    try:
        copies = [_make_copy(work, f"w{i}") for i in range(jobs)]
        _check_no_pyins(copies[0])
        code, out, secs = _pytest(copies[0], PHYSICS_TESTS, None)
        if code != 0:
            print(out[-3000:])
            sys.exit("mutation: the unmutated physics tests fail; fix them first")
        print(f"baseline: physics subset passes unmutated in {secs:.0f} s")
        free = list(copies)
        lock = threading.Lock()

        def one(m: Mutation) -> None:
            with lock:
                copy = free.pop()
            try:
                saved = _apply(copy, m)
                try:
                    code, out, secs = _pytest(copy, PHYSICS_TESTS, QUICK_TIMEOUT)
                finally:
                    for path, text in saved.items():
                        path.write_text(text)
                if code == -9:
                    verdict = "killed (timeout)"
                elif code == 0:
                    verdict = "SURVIVED"
                elif code in (1, 2, 3):  # failures, interrupted (collection/import errors)
                    verdict = "killed"
                else:
                    verdict = f"SURVIVED (pytest exit {code})"
                results[m.name] = (verdict, secs)
                print(f"  {verdict:17s} {m.name:32s} {secs:5.0f} s  {m.what}", flush=True)
            finally:
                with lock:
                    free.append(copy)

        with ThreadPoolExecutor(max_workers=jobs) as pool:
            list(pool.map(one, chosen))
    except KeyboardInterrupt:
        _kill_all()
        print("\ninterrupted: test processes ended, temporary copies removed", file=sys.stderr)
        raise
    finally:
        _kill_all()
        shutil.rmtree(work, ignore_errors=True)
    equivalent = [m for m in chosen if m.equivalent]
    killed = sum(results[m.name][0].startswith("killed") for m in chosen if not m.equivalent)
    total = len(chosen) - len(equivalent)
    survivors = [m.name for m in chosen if not m.equivalent and results[m.name][0] == "SURVIVED"]
    print(f"killed {killed} of {total} ({len(equivalent)} documented equivalent)")
    if survivors:
        print("survived: " + ", ".join(survivors))
    score = killed / total if total else 1.0
    print(f"mutation_score: {score:.3f}")
    return score


# --- full mode (mutmut) ------------------------------------------------------------------


def load_equivalents() -> dict[str, str]:
    """Documented equivalent mutants: mutant name (or fnmatch pattern) -> reason."""
    if not EQUIVALENTS.exists():
        return {}
    data = tomllib.loads(EQUIVALENTS.read_text())
    return {e["mutant"]: e["reason"] for e in data.get("equivalent", [])}


def _mutmut(copy: Path, *args: str, timeout: float | None = None) -> tuple[int, str, float]:
    code = (
        "import sys; sys.modules['pyins'] = None; "
        f"sys.argv = ['mutmut', *{list(args)!r}]; "
        "from mutmut.__main__ import cli; cli()"
    )
    return _run([sys.executable, "-c", code], copy, timeout)


def _statuses(copy: Path, only: list[str] | None = None) -> dict[str, str]:
    """mutmut's verdict of every mutant in :data:`FULL_SCOPE` ("killed", "survived", ...),
    restricted to the names matching one of ``only`` when given."""
    code, out, _ = _mutmut(copy, "results", "--all", "true")
    status: dict[str, str] = {}
    for line in out.splitlines():
        name, sep, verdict = line.strip().rpartition(": ")
        if sep and name.startswith("inserr."):
            status[name] = verdict.strip()
    scope = {n: s for n, s in status.items() if any(fnmatch.fnmatch(n, p) for p in FULL_SCOPE)}
    if only:
        scope = {n: s for n, s in scope.items() if any(fnmatch.fnmatch(n, p) for p in only)}
    return scope


def full(
    jobs: int,
    workdir: Path | None,
    keep: bool,
    survivors_only: bool = False,
    score_only: bool = False,
    only: list[str] | None = None,
) -> float:
    try:
        import mutmut  # noqa: F401
    except ImportError:
        sys.exit("mutation: the full mode needs mutmut (pip install '.[test]')")
    own = workdir is None
    work = Path(tempfile.mkdtemp(prefix="inserr-mutmut-")) if own else workdir
    work.mkdir(parents=True, exist_ok=True)
    try:
        copy = work / "tree"
        if not copy.exists():
            copy = _make_copy(work, "tree")
        elif not score_only:  # a kept work directory: refresh sources and tests, keep the cache
            for item in COPY:
                src, dst = ROOT / item, copy / item
                if src.is_dir():
                    shutil.rmtree(dst, ignore_errors=True)
                    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("__pycache__"))
                elif src.exists():
                    shutil.copy2(src, dst)
        _check_no_pyins(copy)
        # --mutants: a part of the core (e.g. one module), scored on its own.
        names = list(only) if only else list(FULL_SCOPE)
        if survivors_only and (copy / "mutants").exists():
            # Rerun only what the last run did not kill (new tests, same mutants). mutmut
            # records which tests reach which function once, and later adds only tests
            # with new names: forget the record if a test file changed since, so that
            # changed tests count too.
            stats = copy / "mutants" / "mutmut-stats.json"
            newest = max(f.stat().st_mtime for f in (ROOT / "tests").glob("*.py"))
            if stats.exists() and newest > stats.stat().st_mtime:
                stats.unlink()
            names = [n for n, s in _statuses(copy, only).items() if s not in ("killed", "timeout")]
            print(f"rerunning the {len(names)} mutants in scope not killed last time")
        print(f"full mode: mutmut in {copy} ({jobs} children); this takes a while")
        code, out, secs = 0, "", 0.0
        if names and not score_only:
            code, out, secs = _mutmut(copy, "run", "--max-children", str(jobs), *names)
        (work / "mutmut-run.log").write_text(out)
        if code != 0:
            print(out[-3000:])
            sys.exit(f"mutation: mutmut run failed (exit {code})")
        in_scope = _statuses(copy, only)
        equivalents = load_equivalents()

        def is_equivalent(name: str) -> bool:
            return any(name == k or fnmatch.fnmatch(name, k) for k in equivalents)

        killed = [n for n, s in in_scope.items() if s in ("killed", "timeout")]
        eq = [n for n, s in in_scope.items() if is_equivalent(n) and s not in ("killed", "timeout")]
        other = {n: s for n, s in in_scope.items() if n not in killed and n not in eq}
        total = len(in_scope) - len(eq)
        print(
            f"mutants in scope: {len(in_scope)}; killed {len(killed)}; "
            f"documented equivalent {len(eq)}; not killed {len(other)} ({secs / 60:.0f} min)"
        )
        for n, s in sorted(other.items()):
            print(f"  {s:10s} {n}")
        unchecked = [n for n, s in other.items() if s == "not checked"]
        checked = total - len(unchecked)
        if unchecked:
            print(
                f"{len(unchecked)} mutants not checked (run interrupted); over the "
                f"{checked} checked: {len(killed) / checked:.3f}"
            )
        score = len(killed) / total if total else 1.0
        print(f"mutation_score: {score:.3f}")
        if keep or not own:
            print(f"mutmut work directory kept: {copy} (mutmut show NAME there)")
        return score
    except KeyboardInterrupt:
        _kill_all()
        print("\ninterrupted: mutmut ended", file=sys.stderr)
        raise
    finally:
        _kill_all()
        if own and not keep:
            shutil.rmtree(work, ignore_errors=True)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="the fixed list of targeted mutations")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 2, help="parallel runs")
    ap.add_argument("--only", nargs="*", default=[], help="quick: run only these names/patterns")
    ap.add_argument("--list", action="store_true", help="quick: print the list and exit")
    ap.add_argument("--workdir", type=Path, help="full: reuse this mutmut work directory")
    ap.add_argument("--keep", action="store_true", help="full: keep the mutmut work directory")
    ap.add_argument(
        "--score-only",
        action="store_true",
        help="full, with --workdir of an earlier run: recompute the score, run nothing",
    )
    ap.add_argument(
        "--survivors-only",
        action="store_true",
        help="full, with --workdir of an earlier run: rerun only the mutants it did not kill",
    )
    ap.add_argument(
        "--mutants",
        nargs="+",
        metavar="PATTERN",
        help="full: only the mutants whose names match these patterns, e.g. "
        "'inserr.schemes.composition.*' (one module); the score is over them only",
    )
    args = ap.parse_args(argv)
    if args.list:
        for m in QUICK:
            print(f"{m.name:32s} {m.edits[0][0]:36s} {m.what}")
        print(f"{len(QUICK)} mutations")
        return 0
    if args.quick:
        quick(max(1, args.jobs), args.only)
    else:
        full(
            max(1, args.jobs),
            args.workdir,
            args.keep,
            args.survivors_only,
            args.score_only,
            args.mutants,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
