"""The momentum observer in Python (no rclpy): its filter design, the momentum of a whole log, the observer sample
by sample (the shell of the compiled step, :mod:`fsr_estimation.core.observer_step`) and on a whole log, the
estimator on stamped samples, and the quality of an estimate. The per-step code is compiled, in
:mod:`fsr_estimation.core`."""
