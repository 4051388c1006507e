"""Sweeps: many closed-loop flights of one scenario as one table (:func:`fsr_bringup.sweeps.run.sweep`, the
``fsr-sweep`` command)."""
