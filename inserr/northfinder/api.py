"""The notebook front door of the north finder: ``inserr.northfind``.

:func:`northfind` runs the Monte Carlo of a ``northfinder`` scenario beside its
Cramér-Rao bound (as ``inserr northfind``) and returns a :class:`NorthfinderStudy`
with the common interface (:class:`~inserr.output.results.StudyResult`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from inserr.core.units import MIL
from inserr.northfinder.inputs import NorthfinderInputs, northfinder_inputs
from inserr.northfinder.study import MonteCarloResult, monte_carlo
from inserr.output.results import TOTAL_LABEL, StudyResult
from inserr.scenario.schema import Scenario, as_scenario

if TYPE_CHECKING:  # pragma: no cover - typing only
    import pandas as pd
    from matplotlib.figure import Figure


def northfind(scenario: Scenario | str | Path | dict | None = None) -> NorthfinderStudy:
    """Monte Carlo of the rotation-modulation north finder (``inserr.northfind``).

    Parameters
    ----------
    scenario : Scenario, str, Path, dict or None
        A ``northfinder`` scenario (its defaults fill absent keys: 3-minute runs, 50
        runs, ...); None: the defaults alone.

    Returns
    -------
    NorthfinderStudy
    """
    scen = as_scenario({} if scenario is None else scenario, "northfinder")
    inp = northfinder_inputs(scen)
    result = monte_carlo(
        inp.pose,
        inp.instrument,
        inp.grade,
        inp.duration,
        n_runs=inp.runs,
        seed=inp.seed,
        latitude_known=inp.latitude_known,
        hemisphere=inp.hemisphere,
    )
    return NorthfinderStudy(scen, inp, result)


@dataclass
class NorthfinderStudy(StudyResult):
    """A north-finder Monte Carlo and its bounds.

    Attributes
    ----------
    scenario : Scenario
    inputs : NorthfinderInputs
    result : MonteCarloResult
    """

    scenario: Scenario
    inputs: NorthfinderInputs
    result: MonteCarloResult

    @property
    def title(self) -> str:  # type: ignore[override]
        return f"inserr north finder: {self.scenario.name}"

    def metrics(self) -> dict[str, Any]:
        """The Monte Carlo summary (as ``inserr northfind --json``)."""
        return {
            **self.result.summary(),
            "latitude_known": bool(self.inputs.latitude_known),
            "seed": self.inputs.seed,
        }

    def to_dataframe(self) -> pd.DataFrame:
        """Per filter period: heading error 1 sigma and bias (Monte Carlo) and the bounds.

        Columns ``time (s)``, heading in mil, latitude in deg (absent when the
        latitude is given to the estimator).
        """
        import pandas as pd

        r = self.result
        cols: dict[str, Any] = {
            "time (s)": r.times,
            "heading error 1-sigma, Monte Carlo (mil)": r.heading_sigma() / MIL,
            "heading error bias, Monte Carlo (mil)": r.heading_bias() / MIL,
            "heading error bound, white noise (mil)": r.bound.heading / MIL,
            "heading error bound, with bias instability (mil)": r.bound_bi.heading / MIL,
        }
        if not r.latitude_known:
            cols["latitude error 1-sigma, Monte Carlo (deg)"] = np.degrees(r.lat_sigma())
            cols["latitude error bound, white noise (deg)"] = np.degrees(r.bound.lat)
        return pd.DataFrame(cols)

    def budget(self) -> pd.DataFrame:
        """The heading-error bound at the end, by source: white noise, bias instability.

        The white-noise Cramér-Rao bound and the bound with the bias instability (its
        PSD at the table frequency added) are independent contributions: the bias
        instability's share is the root-difference-square, and the total (the bound
        with bias instability) their root-sum-square. Beside it, the Monte Carlo.
        """
        import pandas as pd

        r = self.result
        white = float(r.bound.heading[-1] / MIL)
        total = float(r.bound_bi.heading[-1] / MIL)
        bi = math.sqrt(max(total**2 - white**2, 0.0))
        mc = float(r.heading_sigma()[-1] / MIL)
        return pd.DataFrame(
            {"heading error 1-sigma at the end (mil)": [white, bi, total, mc]},
            index=pd.Index(
                [
                    "sensor white noise (ARW, VRW): Cramér-Rao bound",
                    "bias instability (asymptotic bound)",
                    TOTAL_LABEL,
                    "Monte Carlo (for comparison)",
                ],
                name="source",
            ),
        )

    def plot(self) -> Figure:
        """Heading error vs time: Monte Carlo 1 sigma and bias beside the bound."""
        from inserr.northfinder.figures import heading_history_figure

        return heading_history_figure(self.result, self.title)

    def _summary_metrics(self) -> list[tuple[str, Any]]:
        s = self.result.summary()
        return [
            ("runs", s["runs"]),
            ("duration (s)", s["duration_s"]),
            ("heading error 1-sigma (mil)", s["heading_error_1sigma_mil"]),
            ("heading bound, white noise (mil)", s["crlb_heading_mil"]),
            ("heading sigma / bound", s["heading_sigma_over_crlb"]),
            ("latitude error 1-sigma (deg)", s["latitude_error_1sigma_deg"]),
        ]
