"""The parts of greedy-ce's decision over closed prefix sets; :mod:`..greedy_search` is the
driver and states the mathematics (paper Section IV-A, Eqs. 3-7).

* :mod:`.levels`: the prefix sets, level by level, and what ``done`` alone fixes (the window);
* :mod:`.bounds`: the optimistic score of a prefix and the kit-fitness bound it uses;
* :mod:`.rests`: the best rest of the window after a prefix (decomposition, or search);
* :mod:`.frontier`: the best-first queue of prefixes and the beam's selection.
"""
