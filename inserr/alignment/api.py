"""The notebook front door of the alignment study: ``inserr.align``.

:func:`align` runs the alignment filter of a scenario under one or more schemes (as
``inserr align``) and returns an :class:`AlignmentStudy` with the common interface
(:class:`~inserr.output.results.StudyResult`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from inserr.alignment.filter import (
    STATES,
    UNITS,
    AlignmentResult,
    Prior,
    Settings,
    report_transform,
    static_floors,
)
from inserr.alignment.inputs import AlignmentInputs, alignment_inputs
from inserr.alignment.study import SHOWN, alignment_timeline, run_schemes
from inserr.core.earth import Site
from inserr.core.imu import ImuErrors
from inserr.model.timeline import Timeline
from inserr.output.results import TOTAL_LABEL, StudyResult
from inserr.scenario.schema import Scenario, as_scenario

if TYPE_CHECKING:  # pragma: no cover - typing only
    import pandas as pd
    from matplotlib.figure import Figure

#: Readable names of the reported states.
STATE_LABELS = {
    "phi_e": "east tilt error",
    "phi_n": "north tilt error",
    "phi_u": "heading error",
    "dv_e": "east velocity error",
    "dv_n": "north velocity error",
    "dv_u": "up velocity error",
    "dr_e": "east position error",
    "dr_n": "north position error",
    "dr_u": "up position error",
    "gyro_bias_x": "gyro bias, x axis",
    "gyro_bias_y": "gyro bias, y axis",
    "gyro_bias_z": "gyro bias, z axis",
    "accel_bias_x": "accelerometer bias, x axis",
    "accel_bias_y": "accelerometer bias, y axis",
    "accel_bias_z": "accelerometer bias, z axis",
}
_UNIT_TEXT = {"arcsec": "arcsec", "arcmin": "arcmin", "mm_s": "mm/s", "m": "m", "deg_h": "deg/h"}


def state_unit(state: str) -> str:
    """Unit text of a reported state (``arcsec``, ``arcmin``, ``mm/s``, ``m``, ``deg/h``, ug)."""
    key = UNITS[state][0]
    for suffix, text in _UNIT_TEXT.items():
        if key.endswith("_" + suffix):
            return text
    return "ug"


#: The error sources of an alignment, in budget order: the prior's groups, the sensor
#: noise, the measurement noise.
ALIGNMENT_SOURCES = {
    "attitude": "initial attitude error (prior)",
    "velocity": "initial velocity error (prior)",
    "position": "initial position error (prior)",
    "gyro_bias": "gyro bias (prior)",
    "accel_bias": "accelerometer bias (prior)",
    "arw": "gyro angle random walk (ARW)",
    "vrw": "accelerometer velocity random walk (VRW)",
    "zupt": "zero-velocity measurement noise",
    "position_updates": "position measurement noise",
}
_PRIOR_SLICES = {
    "attitude": slice(0, 3),
    "velocity": slice(3, 6),
    "position": slice(6, 9),
    "gyro_bias": slice(9, 12),
    "accel_bias": slice(12, 15),
}


def source_budget(
    site: Site,
    timeline: Timeline,
    imu: ImuErrors,
    prior: Prior | None = None,
    settings: Settings | None = None,
) -> dict[str, np.ndarray]:
    """Final variance of every reported state, split by error source (exact).

    The filter's estimation error is linear in its sources — the prior's groups
    (attitude, velocity, position, gyro and accelerometer biases, independent), the
    white noise of the gyros and accelerometers, and the measurement noise — through
    the gains the filter computes. Carrying one covariance per source through the
    same transitions and the same gains, ``P_j+ = (I - K H) P_j- (I - K H)^T + K R_j
    K^T``, splits the filter's own (Joseph-form) covariance exactly: the variances
    add up to the filter's, to round-off.

    Parameters
    ----------
    site, timeline, imu, prior, settings
        As :func:`inserr.alignment.filter.run_alignment`.

    Returns
    -------
    dict
        Source key (:data:`ALIGNMENT_SOURCES`, only those present) -> (15,) final
        variances of the reported states (:data:`STATES`, SI squared).
    """
    from inserr.alignment.observability import measurement_matrix
    from inserr.model.discretization import Discretizer
    from inserr.model.exact_propagation import make_steps
    from inserr.model.psi_model import ErrorModel, Layout

    prior = prior or Prior()
    settings = settings or Settings()
    model = ErrorModel(site, Layout(bias=True), vertical=settings.vertical)
    n = model.layout.n
    discs = {"arw": Discretizer(model, model.noise_intensity(imu.arw, 0.0))}
    discs["vrw"] = Discretizer(model, model.noise_intensity(0.0, imu.vrw))
    n_meas = int(math.floor(timeline.duration * settings.zupt_rate + 1e-9))
    t_meas = np.arange(1, n_meas + 1) / settings.zupt_rate
    steps = make_steps(timeline, t_meas, use_omega=True)
    phis = discs["arw"].transitions(steps.unique_omega, steps.unique_dt)
    h = measurement_matrix(model, settings.position_sigma is not None)
    m = h.shape[0]
    r_parts = {"zupt": np.zeros(m), "position_updates": np.zeros(m)}
    if settings.position_sigma is None:
        r_parts["zupt"][:] = settings.zupt_sigma**2
        del r_parts["position_updates"]
    else:
        r_parts["zupt"][: m // 2] = settings.zupt_sigma**2
        r_parts["position_updates"][m // 2 :] = settings.position_sigma**2
    r = sum(r_parts.values())
    sig0 = prior.sigma()
    if settings.vertical == "clamped":
        sig0[[5, 8]] = 0.0
    m0_inv = np.linalg.inv(report_transform(model, timeline.c_sn[0]))
    parts: dict[str, np.ndarray] = {}
    for key, sl in _PRIOR_SLICES.items():
        d = np.zeros(len(STATES))
        d[sl] = sig0[sl] ** 2
        parts[key] = m0_inv @ np.diag(d) @ m0_inv.T
    for key in ("arw", "vrw", *r_parts):
        parts[key] = np.zeros((n, n))
    attitudes = timeline.attitude_at(t_meas)
    eye = np.eye(n)
    final = {k: np.zeros(len(STATES)) for k in parts}
    for i in range(len(steps.dt)):
        k = int(steps.key[i])
        phi = phis[k]
        for key, p in parts.items():
            p = phi @ p @ phi.T
            if key in discs:
                p = p + discs[key].noise(steps.unique_omega[k], steps.unique_dt[k])
            parts[key] = p
        rec = int(steps.record[i])
        if rec < 0:
            continue
        p_total = sum(parts.values())
        s = h @ p_total @ h.T + np.diag(r)
        gain = np.linalg.solve(s, h @ p_total).T  # K = P H^T S^-1 (S symmetric)
        a = eye - gain @ h
        for key, p in parts.items():
            p = a @ p @ a.T
            if key in r_parts:
                p = p + gain @ np.diag(r_parts[key]) @ gain.T
            parts[key] = 0.5 * (p + p.T)
        mt = report_transform(model, attitudes[rec])
        for key, p in parts.items():
            final[key] = np.clip(np.diag(mt @ p @ mt.T), 0.0, None)
    return {k: v for k, v in final.items() if np.any(v > 0)}


def align(
    scenario: Scenario | str | Path | dict | None = None, schemes: Iterable[str] | None = None
) -> AlignmentStudy:
    """Fine alignment of a scenario under its scheme(s) (``inserr.align``).

    Parameters
    ----------
    scenario : Scenario, str, Path, dict or None
        An ``alignment`` scenario (its defaults fill absent keys: 10 minutes, 60 s
        stops, ...); None: the defaults alone.
    schemes : iterable of str, optional
        Schemes run on the same base (default: the scenario's, as ``inserr align``).

    Returns
    -------
    AlignmentStudy
    """
    scen = as_scenario({} if scenario is None else scenario, "alignment")
    inp = alignment_inputs(scen)
    names = (
        list(inp.schemes)
        if schemes is None
        else [schemes]
        if isinstance(schemes, str)
        else list(schemes)
    )
    results = run_schemes(inp.base, names, inp.duration, inp.imu, inp.prior, inp.settings)
    return AlignmentStudy(scen, inp, results)


@dataclass
class AlignmentStudy(StudyResult):
    """Alignment filter results of several schemes on one base.

    Attributes
    ----------
    scenario : Scenario
    inputs : AlignmentInputs
    results : dict
        Scheme -> :class:`~inserr.alignment.filter.AlignmentResult` (``study[name]``).
    """

    scenario: Scenario
    inputs: AlignmentInputs
    results: dict[str, AlignmentResult]

    @property
    def title(self) -> str:  # type: ignore[override]
        return f"inserr alignment: {self.scenario.name}"

    def __getitem__(self, name: str) -> AlignmentResult:
        return self.results[name]

    def metrics(self) -> dict[str, Any]:
        """Per scheme: final 1 sigma, convergence time, observability degree, final error.

        Also the static floors of the unindexed IMU on this base (arcsec, arcmin).
        """
        inp = self.inputs
        c0 = inp.base.motion.attitude(0.0)[0]
        floor = static_floors(inp.base.site, inp.prior.gyro_bias, inp.prior.accel_bias, c0)
        return {
            "minutes": inp.duration / 60.0,
            "lat_deg": math.degrees(inp.base.site.lat),
            "static_floor_diffuse_prior": {
                "phi_e_arcsec": floor["phi_e"] / UNITS["phi_e"][1],
                "phi_n_arcsec": floor["phi_n"] / UNITS["phi_n"][1],
                "phi_u_arcmin": floor["phi_u"] / UNITS["phi_u"][1],
            },
            "runs": {name: r.summary() for name, r in self.results.items()},
        }

    def to_dataframe(self) -> pd.DataFrame:
        """The 1 sigma of the shown states over time, every scheme (long format).

        Columns ``scheme``, ``time (s)`` and ``<state> 1-sigma (<unit>)``.
        """
        import pandas as pd

        frames = []
        for name, r in self.results.items():
            cols: dict[str, Any] = {"scheme": name, "time (s)": r.t}
            for s in SHOWN:
                i = STATES.index(s)
                cols[f"{STATE_LABELS[s]} 1-sigma ({state_unit(s)})"] = r.sigma[:, i] / UNITS[s][1]
            frames.append(pd.DataFrame(cols))
        return pd.concat(frames, ignore_index=True)

    def budget(self, scheme: str | None = None) -> pd.DataFrame:
        """The final attitude error by source: what limits the alignment, per scheme.

        Exact split of the filter's final covariance (:func:`source_budget`): rows
        the sources (prior groups, sensor noise, measurement noise), columns the
        east and north tilt errors (arcsec) and the heading error (arcmin) at the end,
        1 sigma; the root-sum-square total (the filter's own 1 sigma) last.

        Parameters
        ----------
        scheme : str, optional
            One scheme (default: every scheme, a ``scheme`` column level).
        """
        import pandas as pd

        names = [scheme] if scheme is not None else list(self.results)
        inp = self.inputs
        frames = {}
        cols = [f"{STATE_LABELS[s]} ({state_unit(s)})" for s in ("phi_e", "phi_n", "phi_u")]
        idx = [STATES.index(s) for s in ("phi_e", "phi_n", "phi_u")]
        scale = np.array([UNITS[s][1] for s in ("phi_e", "phi_n", "phi_u")])
        for name in names:
            tl = alignment_timeline(inp.base, name, inp.duration)
            parts = source_budget(inp.base.site, tl, inp.imu, inp.prior, inp.settings)
            rows = {ALIGNMENT_SOURCES[k]: np.sqrt(v[idx]) / scale for k, v in parts.items()}
            total = np.sqrt(sum(v[idx] for v in parts.values())) / scale
            rows[TOTAL_LABEL] = total
            frames[name] = pd.DataFrame.from_dict(rows, orient="index", columns=cols)
            frames[name].index.name = "source"
        if scheme is not None:
            return frames[scheme]
        return pd.concat(frames, axis=1, names=["scheme", "error"])

    def plot(self) -> Figure:
        """1 sigma of attitude and biases during alignment, every scheme."""
        from inserr.alignment.figures import sigma_figure

        return sigma_figure(self.results)

    def _summary_metrics(self) -> list[tuple[str, Any]]:
        rows: list[tuple[str, Any]] = [("alignment time (min)", self.inputs.duration / 60.0)]
        for name, r in self.results.items():
            for s in ("phi_e", "phi_n", "phi_u"):
                rows.append(
                    (
                        f"{name}: final {STATE_LABELS[s]} 1-sigma ({state_unit(s)})",
                        float(r.final_sigma[STATES.index(s)] / UNITS[s][1]),
                    )
                )
        return rows
