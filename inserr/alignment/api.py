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

from inserr.alignment.filter import STATES, UNITS, AlignmentResult, static_floors
from inserr.alignment.inputs import AlignmentInputs, alignment_inputs
from inserr.alignment.study import SHOWN, run_schemes
from inserr.output.results import TOTAL_LABEL, StudyResult, rss
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

    def budget(self) -> pd.DataFrame:
        """Final 1 sigma of the attitude errors and of the biases, per scheme.

        The attitude rows end with the total tilt (root-sum-square of the east and
        north tilt errors, arcsec): the level error an alignment leaves.
        """
        import pandas as pd

        index = [STATE_LABELS[s] for s in SHOWN] + [f"{TOTAL_LABEL}: tilt"]
        data: dict[str, Any] = {"unit": [state_unit(s) for s in SHOWN] + ["arcsec"]}
        for name, r in self.results.items():
            vals = [float(r.final_sigma[STATES.index(s)] / UNITS[s][1]) for s in SHOWN]
            data[name] = vals + [rss(vals[:2])]
        return pd.DataFrame(data, index=pd.Index(index, name="state"))

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
