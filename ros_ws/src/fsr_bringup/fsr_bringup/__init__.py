"""fsr_bringup: fsr-fly (node graph or in-process), fsr-record, fsr-analyze, fsr-sweep, fsr-tune, fsr-vehicle,
fsr-compile, and the Python API.

``from fsr_bringup import simulate`` (:func:`fsr_bringup.api.simulate`), ``from fsr_bringup import sweep``
(:func:`fsr_bringup.sweeps.run.sweep`: many flights as one table), ``from fsr_bringup import tune``
(:func:`fsr_bringup.tuning.study.tune`: parameters found by optimisation).
"""

from typing import Any


def __getattr__(name: str) -> Any:
    # Lazy: importing fsr_bringup (e.g. for a console script) does not import the whole stack.
    if name in ("simulate", "FlightRun"):
        from fsr_bringup import api

        return getattr(api, "FlightRun" if name == "FlightRun" else "simulate")
    if name == "sweep":
        from fsr_bringup.sweeps.run import sweep

        return sweep
    if name == "tune":
        from fsr_bringup.tuning.study import tune

        return tune
    raise AttributeError(f"module 'fsr_bringup' has no attribute '{name}'")


__all__ = ["FlightRun", "simulate", "sweep", "tune"]
