"""Design optimisation: IPOPT on the sweep's vocabulary, and the front in the sweep's own metrics.

Modules: :mod:`.runner` (``optimise``), its problem, settings, results, starts, evaluation budget,
contacts, the shaping-range objective, the dense check (:mod:`.dense_check`), and :mod:`.sweep_front`
on the smooth twins of :mod:`.sweep_surrogate` and their quadratic models in :mod:`.front_model`.
"""
