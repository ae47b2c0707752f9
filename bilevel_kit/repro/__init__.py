"""Reproduction of the paper's user study (Section V-A, Fig. 5 top) and Figure 6 (Section V-B).

The entry points the CLI (``bilevel-kit repro calibrate|user-study|fig6|horizon|adaptive|
stations``) calls (``run_adaptive`` lives in :mod:`.adaptive`, ``run_stations`` in
:mod:`.stations`)::

    run_calibration(out_dir="out/repro/calibration", quick=False, seed=0, jobs=1) -> dict
    run_user_study(out_dir="out/repro/user_study", quick=False, seed=0, jobs=1) -> dict
    run_fig6(out_dir="out/repro/fig6", quick=False, reps=None, jobs=1,
             delivery_time=None, seed=0) -> dict
    run_horizon(out_dir="out/repro/horizon", quick=False, jobs=1, seed=0) -> dict

All take further keyword-only options (see their docstrings), write their results atomically
under ``out_dir`` and return a JSON-serialisable summary with the output paths under
``"files"``. Modules: :mod:`.calibrated` (the one committed calibration and its bootstrap;
``run_calibration``, ``load_calibration``), :mod:`.calibration` (the protocol's fit),
:mod:`.user_study`, :mod:`.predictions` (fitted, implied and predicted paper numbers),
:mod:`.within` (the participant model explained), :mod:`.sensitivity`, :mod:`.fig6` and
:mod:`.fig6_stats` (by direction, trends, power), :mod:`.horizon`, :mod:`.adaptive` and
:mod:`.stations` (beyond the paper), :mod:`.stats` (ANOVA, Tukey HSD, t-tests), :mod:`.plots`
(figures), :mod:`.report`, :mod:`.report_sim`, :mod:`.facts` and :mod:`.template` (the
documents rendered from the committed CSVs), :mod:`.common` (the paper's numbers).
``paper_repro/README.md`` documents the choices and the results (docs/reproduction.md).

Choices that apply to the user study and Figure 6 (why, in short):

* **Human idle time.** The paper's idle time is the time the participant was *not actively
  assembling*, so taking the parts off the tray counts as idle. The simulation's
  ``human_idle`` counts the per-kit pickup ``o_H`` as work; the paper-comparable value is
  ``makespan - sum of the sampled task times`` = ``human_idle + n_kits * o_H``
  (:func:`.common.paper_idle`). Every "idle" below is this one.
* **One tray** (``instances/hrc_table.json`` has ``trays: 1``): the study's protocol, "the
  robot returned to its kitting task once the participant retrieved the parts". The Figure 6
  simulation samples the study's times, so it keeps the protocol by default (the keyword
  ``trays="unlimited"`` lets the robot run ahead and stack kits at the human,
  docs/timeline.md).
* **One calibration.** A declared protocol on its own cohort (:mod:`.calibration`), run once
  by ``repro calibrate`` and committed (:mod:`.calibrated`): ``robot_scale`` and
  ``kit_overhead_human`` fitted to Whole Assembly idle 270 s and Single Task idle 99 s, the
  participant x condition SD to the paper's F(2, 34) of total time. Every study reads it.
"""

from __future__ import annotations

from ..sim import TimingModel
from .calibrated import Calibration, load_calibration, run_calibration
from .calibration import Cohort, calibrate, condition_means, draw_cohort, study_params, study_runs
from .common import *  # noqa: F403 (the paper's numbers and helpers: common.__all__)
from .common import __all__ as common_names
from .fig6 import (
    Fig6Cell,
    calibrated_timing,
    comparisons,
    fig6_cell,
    format_fig6_markdown,
    run_fig6,
    summarize_cell,
)
from .horizon import horizon_cell, run_horizon
from .plots import plot_fig6, plot_fig6_panel, plot_horizon, plot_user_study
from .predictions import inside_count, paper_numbers, prediction_table
from .stats import anova_rm, stars, tukey_pairs
from .user_study import format_study_markdown, run_user_study, summarize_study

__all__ = [
    *common_names,
    "Calibration",
    "Cohort",
    "Fig6Cell",
    "TimingModel",
    "anova_rm",
    "calibrate",
    "calibrated_timing",
    "comparisons",
    "condition_means",
    "draw_cohort",
    "fig6_cell",
    "format_fig6_markdown",
    "format_study_markdown",
    "horizon_cell",
    "inside_count",
    "load_calibration",
    "paper_numbers",
    "plot_fig6",
    "plot_fig6_panel",
    "plot_horizon",
    "plot_user_study",
    "prediction_table",
    "run_calibration",
    "run_fig6",
    "run_horizon",
    "run_user_study",
    "stars",
    "study_params",
    "study_runs",
    "summarize_cell",
    "summarize_study",
    "tukey_pairs",
]
