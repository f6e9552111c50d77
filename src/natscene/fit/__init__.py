"""Fitting cloud rendering parameters to a photograph (Dobashi et al. 2012, §3, §4.2, §5.1).

Modules: ``objective`` (Eq. 2 and the other metrics), ``kappa`` (the kappa_a line search of Fig. 3 with
Eq. 3), ``genetic`` (the GA of §4.2), ``gradient`` (the §5.1 baseline), ``problem`` (tables + photo ->
O(c)), ``keyframe`` (one keyframe's fit end to end), ``report`` (contact sheet, convergence plot),
``settings`` (the config section ``fit``), ``synthetic`` (a sphere problem with a known answer).
"""

__all__: list[str] = []  # a map of the package; import the module you need
