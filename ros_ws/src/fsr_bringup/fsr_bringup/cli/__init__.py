"""Console scripts of fsr_bringup: ``fsr-fly`` (fly_cli) and ``fsr-analyze`` (analyze_cli)."""
