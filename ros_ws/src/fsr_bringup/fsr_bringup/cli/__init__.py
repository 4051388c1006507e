"""Console scripts of fsr_bringup: ``fsr-fly`` (fly_cli), ``fsr-analyze`` (analyze_cli), ``fsr-compile``
(compile_cli), ``fsr-sweep`` (sweep_cli), ``fsr-tune`` (tune_cli) and ``fsr-vehicle`` (vehicle_cli)."""
