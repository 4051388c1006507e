"""Tuning: a scenario's parameters found by optimisation over many compiled flights (:func:`fsr_bringup.tuning.
study.tune`, the ``fsr-tune`` command)."""
