"""The compiled flight core of whole flights (:mod:`fsr_sim.core.jit`): the in-process closed loop, a sweep's
measurements as it flies, and the effective truth of a step."""
