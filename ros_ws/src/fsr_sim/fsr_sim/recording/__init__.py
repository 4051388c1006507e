"""ROS 2 MCAP recordings: writer, reader and whole-topic decoding (the ``recording`` extra of fsr_sim).

The nodes never import this package: a controller or estimator on a companion computer installs fsr_sim
without ``mcap`` and ``mcap-ros2-support`` (``pip install fsr_sim``); a machine that records or reads
recordings installs them (``pip install 'fsr_sim[recording]'``, which fsr_bringup does).
"""

try:
    import mcap  # noqa: F401
    import mcap_ros2  # noqa: F401
except ModuleNotFoundError as error:
    raise ModuleNotFoundError(f"MCAP recordings need '{error.name}', which is not installed: "
                              "pip install 'fsr_sim[recording]'", name=error.name) from None
