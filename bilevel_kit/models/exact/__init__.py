"""What the exact whole-horizon methods ``cpsat`` and ``milp`` share: one driver
(:mod:`.driver`: the steps of a run over a small backend protocol, :mod:`.backend`; the "task
does not fit alone" outcome, the proven bound and its source), one warm-start loop
(:mod:`.warm`) and one no-model rule (:mod:`.nomodel`: when no model is built, and the LNS
hand-off then; docs/formulations.md, "Model too large").
"""
