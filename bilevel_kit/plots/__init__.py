"""Figures: the robot/human Gantt chart, tray layouts, method comparisons and cross-entropy
convergence, all in the toolkit's one style (:mod:`bilevel_kit.style`, docs/figures.md).

Every ``plot_*`` function draws into ``ax`` when one is given (otherwise it makes a new figure)
and returns the Axes; :func:`plot_trays` makes many Axes and returns the Figure. Nothing here
calls ``plt.show``: write figures with :func:`save_figure`, which also closes them.

The artists carry ``gid`` tags so that tests and callers can find them again:

* Gantt chart: ``robot:kit:<k>``, ``robot:delivery:<k>``, ``robot:tray_wait:<k>``,
  ``robot:idle``, ``human:pickup:<k>``, ``human:task:<task id>``, ``human:idle`` (bar
  Rectangles), ``makespan`` (the vertical line).
* Gantt labels: ``label:kit:<k>``, ``label:task:<task id>`` (texts, inside a bar or on a
  leader), ``leader:label:...`` (the leader lines).
* Tray: ``tray`` (the outline Rectangle), ``part:<part id>`` (one Polygon per placement),
  ``label:part:<part id>`` (its type or key inside it), ``label:parts:<id>,<id>`` (the key of
  small parts on a leader).
* Comparison: ``makespan:<method>`` (the dot), ``noplan:<method>`` (text), ``bound`` (line);
  ``human_idle`` (bars of the idle panel).
* KitBench: ``profile:<method>`` (step lines), ``gap:<method>`` (scatter collections).

Bars of zero duration (no delivery time, no pickup overhead ...) are not drawn. A label that
does not fit inside its bar or part goes beside it on a leader line; a Gantt chart whose task
bars are too narrow even for that lists the tasks by kit under the chart.

One module per figure family: :mod:`.gantt`, :mod:`.trays`, :mod:`.comparison` (methods
compared, gaps to the bound), :mod:`.convergence` and :mod:`.bench` (KitBench's performance
profile and gap against size); :mod:`.common` holds what they share
(:func:`save_figure`). Import every name from here.
"""

from __future__ import annotations

from .bench import plot_gap_vs_size, plot_profile
from .common import save_figure
from .comparison import plot_comparison, plot_gaps
from .convergence import plot_convergence
from .gantt import BAR_HEIGHT, GANTT_WIDTH, HUMAN_Y, ROBOT_Y, plot_gantt, tray_waits
from .trays import (
    TRAY_CELL,
    TRAY_COLUMNS,
    kit_fitness,
    plot_tray,
    plot_trays,
    type_colors,
    type_keys,
    type_swatches,
)

__all__ = [
    "BAR_HEIGHT",
    "GANTT_WIDTH",
    "HUMAN_Y",
    "ROBOT_Y",
    "TRAY_CELL",
    "TRAY_COLUMNS",
    "kit_fitness",
    "plot_comparison",
    "plot_convergence",
    "plot_gantt",
    "plot_gap_vs_size",
    "plot_gaps",
    "plot_profile",
    "plot_tray",
    "plot_trays",
    "save_figure",
    "tray_waits",
    "type_colors",
    "type_keys",
    "type_swatches",
]
