"""One tray: the shelf packer, cross-entropy arrangement, the CP-SAT packer, the convex polish
and the kit-fitness terms (paper Section IV-B, Eqs. 8-11).

A pure library below the method layer: nothing here imports :mod:`bilevel_kit.solvers`, and
importing this package loads neither OR-Tools nor cvxpy.
"""
