"""The parts of the cross-entropy kit arrangement (paper Section IV-B, Algorithm 1).

Import from :mod:`bilevel_kit.heuristics.cross_entropy`, the public face, which holds the
algorithm's description; the modules here are its pieces: :mod:`.params` (parameters and
result), :mod:`.kit` (the kit as arrays and the decision vector), :mod:`.scoring` (scoring a
batch of samples), :mod:`.sampling` (the sampling distribution and its update, one CE run) and
:mod:`.accept` (exact acceptance, push-apart repair, the choice among candidates).
"""
