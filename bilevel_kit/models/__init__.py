"""Exact formulations: the baselines that tell how far a heuristic plan is from optimal.

The CP-SAT schedule (:mod:`.cpsat`, embedded tray packing or logic-based Benders), the CP-SAT
no-overlap-2D tray packer and its bounds (:mod:`.packing`, :mod:`.packing_bounds`), the
Pyomo/HiGHS MILP with its child process (:mod:`.milp`), the exact bilevel MILP over kit columns
(:mod:`.bilevel_milp`), the exact segmentation of a fixed order (:mod:`.segment`), the lower
bounds beyond the closed forms (:mod:`.relax`) and the large-neighbourhood search
(:mod:`.lns`, a matheuristic on CP-SAT windows); their
shared pieces live in :mod:`.common` and :mod:`.budget` (docs/formulations.md).

Models may use the heuristics (warm starts) and the core; the heuristics never import this
package. :mod:`bilevel_kit.methods` imports each model by name on first use, so importing this
package loads no solver back-end.
"""
