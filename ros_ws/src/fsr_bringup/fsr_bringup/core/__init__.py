"""The compiled flight core of whole flights (:mod:`fsr_sim.core.jit`): the in-process closed loop."""
