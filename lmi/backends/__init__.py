"""The back-ends that solve :class:`lmi.KothareProblem`: the toolkit's own interior-point method
(:mod:`lmi.backends.ipm`, the default), Clarabel's own API (:mod:`lmi.backends.clarabel`) and
cvxpy (:mod:`lmi.backends.cvxpy`, the reference); each a :class:`~lmi.backends.base.KothareBackend`
(:mod:`lmi.backends.base`), the first two on the conic data of :mod:`lmi.backends.conic`.
"""
