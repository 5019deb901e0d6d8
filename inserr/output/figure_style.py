"""The one figure style of inserr: sizes, resolution, fonts, grid and a colour per scheme.

Every figure of every study (drift, validation, alignment, calibration, north
finder, sweep, and the analyses' write-ups) is built here and finished here:

* :func:`new_figure` / :func:`subplots` make a :class:`matplotlib.figure.Figure`
  directly — never through :mod:`matplotlib.pyplot`, so no backend is selected, no
  global figure list grows and nothing is ever shown — with constrained layout, so
  titles, labels and colour bars never overlap whatever the fonts;
* :func:`finish` sets the font sizes of every title, axis label, tick label and
  legend to :data:`FONT`, so that figures drawn by different studies look alike
  (the report writer applies it again, harmlessly, to every figure it embeds);
* :func:`png_bytes` renders a figure at :data:`DPI` with a tight bounding box, the
  one way inserr turns a figure into a file;
* :func:`scheme_color` gives every scheme of the catalogue its own colour, the same
  in every figure, so "two-position" is the same blue in a drift report, an
  alignment report and a sweep; :data:`ROLE_COLORS` does the same for reference
  curves (RMS over unknown signs, bounds, the nonlinear reference, ...).

Matplotlib is imported only by the functions that draw, so importing this module
(and :mod:`inserr.output`) costs nothing.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover - typing only
    import numpy as np
    from matplotlib.figure import Figure

#: Resolution of every PNG, dots per inch.
DPI = 110

#: Figure width of one column of panels, in.
WIDTH = 8.0
#: Figure width of side-by-side panels (two to four columns), in.
WIDE = 11.0
#: Height of one row of panels, in.
ROW_HEIGHT = 2.6

#: Font sizes, points.
FONT = {
    "suptitle": 11.0,
    "title": 10.0,
    "label": 9.0,
    "tick": 8.0,
    "legend": 7.0,
    "annotation": 7.0,
}

#: Grid lines: light, behind the data.
GRID_ALPHA = 0.3

#: A colour per scheme of :data:`inserr.schemes.catalogue.SCHEMES` (names as strings:
#: the output layer sits below the schemes and never imports them; a test checks that
#: every catalogue scheme has its own colour here).
SCHEME_COLORS: dict[str, str] = {
    "none": "#7f7f7f",
    "continuous": "#17becf",
    "two-position": "#1f77b4",
    "four-position": "#ff7f0e",
    "four-position-modified": "#2ca02c",
    "flexible-two-position": "#9467bd",
    "heading-isolation": "#8c564b",
    "nulling-two-position": "#e377c2",
    "eight-position": "#bcbd22",
    "sixteen-position": "#393b79",
    "sixteen-position-inserr": "#637939",
    "custom": "#843c39",
}

#: Colours of curves that are not a scheme, the same in every figure.
ROLE_COLORS: dict[str, str] = {
    "reference": "k",  # RMS over unknown signs, covariance 1 sigma, Cramér-Rao bound
    # Worst sign pattern: a grey no scheme uses (always drawn dotted, RMS dashed), so it
    # is never taken for a scheme's curve.
    "worst": "#555555",
    "threshold": "#d62728",  # a requirement or tolerance line
    "linear": "#1f77b4",  # the linear (psi-angle) prediction
    "nonlinear": "#d62728",  # the nonlinear reference
    "difference": "#2ca02c",  # nonlinear minus linear
    "sample": "0.7",  # individual Monte Carlo runs
}

#: Colours of series that are neither schemes nor roles (sweep metrics, stop times, ...).
SERIES_COLORS = (
    "#1f77b4",
    "#ff7f0e",
    "#2ca02c",
    "#d62728",
    "#9467bd",
    "#8c564b",
    "#e377c2",
    "#7f7f7f",
    "#bcbd22",
    "#17becf",
)


def series_color(index: int) -> str:
    """Colour of the ``index``-th series of a figure whose series are not schemes.

    Parameters
    ----------
    index : int
        Position of the series (0-based); the palette repeats after ten.

    Returns
    -------
    str
        A matplotlib colour.
    """
    return SERIES_COLORS[index % len(SERIES_COLORS)]


def scheme_color(name: str, index: int = 0) -> str:
    """Colour of scheme ``name``: its own for a catalogue scheme, else by position.

    Parameters
    ----------
    name : str
        Scheme (run) name, e.g. ``"two-position"``.
    index : int
        Position of the run in its figure, for names outside the catalogue
        (:func:`series_color`).

    Returns
    -------
    str
        A matplotlib colour.
    """
    return SCHEME_COLORS.get(name, series_color(index))


def minmax_decimate(
    x: np.ndarray, y: np.ndarray, columns: int = 2000
) -> tuple[np.ndarray, np.ndarray]:
    """Thin a long curve to what a figure can show: the min and max of each column.

    The samples are cut into ``columns`` consecutive groups; each group keeps its
    smallest and its largest sample, in their order, and the first and last samples
    are always kept. Drawn as a line at a width of at most ``columns`` pixels, the
    thinned curve covers exactly the pixels the full one covers in every column (its
    vertical extent per group is the same), so the figure looks the same; drawing it
    costs ``2 columns`` points instead of ``len(x)``.

    Parameters
    ----------
    x, y : (N,) arrays
        The curve (``x`` increasing).
    columns : int
        Number of groups: at least the number of pixel columns the axes span.

    Returns
    -------
    x, y : arrays
        The kept samples (the input itself when it has at most ``2 columns`` samples).
    """
    import numpy as np

    x = np.asarray(x)
    y = np.asarray(y)
    n = len(y)
    if n <= 2 * columns:
        return x, y
    k = -(-n // columns)  # samples per group
    pad = k * columns - n
    # Pad the last group with its own last sample: it changes neither its min nor max.
    yy = np.concatenate([y, np.full(pad, y[-1])]).reshape(columns, k)
    start = np.arange(columns) * k
    lo = start + yy.argmin(axis=1)
    hi = start + yy.argmax(axis=1)
    idx = np.concatenate([[0], np.minimum(lo, hi), np.maximum(lo, hi), [n - 1]])
    idx = np.unique(np.minimum(idx, n - 1))
    return x[idx], y[idx]


def plot_columns(fig: Figure) -> int:
    """Decimation columns for a curve in ``fig``: twice its width in pixels at :data:`DPI`."""
    return int(2 * fig.get_figwidth() * DPI)


def fixed_grid(
    nrows: int,
    ncols: int,
    *,
    width: float,
    panel_height: float,
    left: float = 0.8,
    right: float = 0.15,
    top: float = 0.65,
    bottom: float = 0.55,
    wspace: float = 0.6,
    hspace: float = 0.25,
    **kwargs: Any,
) -> tuple[Figure, Any]:
    """A figure with a grid of panels at fixed margins (inches), without a layout engine.

    For many-panel figures whose text is known in advance (tick labels of a few
    digits, short titles): the positions are set once, so drawing does not pay for
    constrained layout's measuring pass over every label (about half the drawing
    time of a twelve-panel figure). Render with ``png_bytes(fig, crop=False)``.

    Parameters
    ----------
    nrows, ncols : int
        Grid of panels.
    width : float
        Figure width, in.
    panel_height : float
        Height of one row of panels, in; the figure height follows from it.
    left, right, top, bottom : float
        Margins, in (``top`` holds the suptitle and the first row's titles, ``left``
        the first column's tick labels and y label, ``bottom`` the x tick labels and
        label).
    wspace, hspace : float
        Gaps between columns (room for the next column's y tick labels) and rows, in.
    **kwargs
        Passed to :meth:`~matplotlib.figure.Figure.subplots` (``sharex``, ...).

    Returns
    -------
    fig : matplotlib.figure.Figure
    axes : ndarray of Axes
    """
    from matplotlib.figure import Figure

    height = top + bottom + nrows * panel_height + (nrows - 1) * hspace
    fig = Figure(figsize=(width, height), dpi=DPI)
    panel_w = (width - left - right - (ncols - 1) * wspace) / ncols
    axes = fig.subplots(
        nrows,
        ncols,
        gridspec_kw={
            "left": left / width,
            "right": 1 - right / width,
            "bottom": bottom / height,
            "top": 1 - top / height,
            "wspace": wspace / panel_w,
            "hspace": hspace / panel_height,
        },
        **kwargs,
    )
    return fig, axes


def new_figure(width: float = WIDTH, height: float = 4.2) -> Figure:
    """A new, empty figure in the inserr style (not managed by pyplot, never shown).

    Parameters
    ----------
    width, height : float
        Size, in.

    Returns
    -------
    matplotlib.figure.Figure
        With constrained layout and :data:`DPI`.
    """
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), dpi=DPI, layout="constrained")


def subplots(
    nrows: int = 1,
    ncols: int = 1,
    *,
    width: float = WIDTH,
    height: float | None = None,
    **kwargs: Any,
) -> tuple[Figure, Any]:
    """A new figure with a grid of axes (:meth:`matplotlib.figure.Figure.subplots`).

    Parameters
    ----------
    nrows, ncols : int
        Grid of panels.
    width : float
        Figure width, in.
    height : float, optional
        Figure height, in (default :data:`ROW_HEIGHT` per row plus room for a title).
    **kwargs
        Passed to :meth:`~matplotlib.figure.Figure.subplots` (``sharex``,
        ``squeeze``, ``gridspec_kw``, ...).

    Returns
    -------
    fig : matplotlib.figure.Figure
    axes : Axes or ndarray of Axes
    """
    if height is None:
        height = 1.2 + ROW_HEIGHT * nrows
    fig = new_figure(width, height)
    return fig, fig.subplots(nrows, ncols, **kwargs)


def grid(ax: Any, **kwargs: Any) -> None:
    """Draw the light grid of the inserr style on ``ax`` (``which``/``axis`` allowed)."""
    ax.grid(True, alpha=GRID_ALPHA, **kwargs)


def suptitle(fig: Figure, text: str) -> None:
    """Title of a whole figure, in the style's suptitle size."""
    fig.suptitle(text, fontsize=FONT["suptitle"])


def finish(fig: Figure) -> Figure:
    """Apply the style's font sizes to every axes and legend of ``fig``; return ``fig``.

    Idempotent: the report writer calls it again on every figure it embeds.

    Parameters
    ----------
    fig : matplotlib.figure.Figure

    Returns
    -------
    matplotlib.figure.Figure
        The same figure.
    """
    for ax in fig.axes:
        ax.title.set_fontsize(FONT["title"])
        ax.xaxis.label.set_fontsize(FONT["label"])
        ax.yaxis.label.set_fontsize(FONT["label"])
        ax.tick_params(axis="both", which="both", labelsize=FONT["tick"])
        _legend_fonts(ax.get_legend())
    for legend in fig.legends:
        _legend_fonts(legend)
    return fig


def _legend_fonts(legend: Any) -> None:
    if legend is None:
        return
    for text in legend.get_texts():
        text.set_fontsize(FONT["legend"])
    legend.get_title().set_fontsize(FONT["legend"])


def png_bytes(fig: Figure, metadata: dict[str, str] | None = None, crop: bool = True) -> bytes:
    """The figure as PNG bytes at :data:`DPI`, cropped to its content.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    metadata : dict, optional
        PNG text chunks (e.g. the sweep's figure mark).
    crop : bool
        Crop to the drawn content (``bbox_inches="tight"``), which draws the figure
        twice. False: the figure as laid out (constrained layout already keeps every
        label, title and ``"outside"`` legend inside it), drawn once.

    Returns
    -------
    bytes
    """
    import io

    buf = io.BytesIO()
    fig.savefig(
        buf, format="png", dpi=DPI, bbox_inches="tight" if crop else None, metadata=metadata
    )
    return buf.getvalue()
