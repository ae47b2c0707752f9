"""Exact models and bounds: CP-SAT schedule (:mod:`.cpsat_schedule`), CP-SAT tray packing
(:mod:`.cpsat_packing`) and closed-form lower bounds (:mod:`.bounds`).

Kept import-free on purpose: importing ``bilevel_kit.models`` must not load OR-Tools.
"""
