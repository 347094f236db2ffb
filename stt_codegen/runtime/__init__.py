"""Running a designed controller: backends, plants, the sampled closed loop, figures.

Contract: every backend (:mod:`.backends`) steps ``(x, t, dt, alpha) -> (u, alpha_next,
status)``; :func:`.simulate.simulate` runs one against a python-control plant
(:mod:`.plants`) and judges Definition 2.1.
"""

__all__: list[str] = []
