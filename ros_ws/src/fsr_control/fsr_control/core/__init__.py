"""The compiled flight core of the controller (:mod:`fsr_sim.core.jit`): reference sampling, flatness, the
geometric and Voliro laws, allocation with desaturation and the null-space objective, disturbance
compensation, and the controller's per-step tick."""
