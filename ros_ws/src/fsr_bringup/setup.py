from setuptools import find_packages, setup

package_name = "fsr_bringup"

setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    package_data={"fsr_bringup": ["fleets/*.yaml"]},
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
    ],
    install_requires=[
        "setuptools", "numpy", "matplotlib", "PyYAML", "mcap", "mcap-ros2-support", "ros-rosidl-parser",
        "pandas", "dask[distributed]", "pillow", "imageio-ffmpeg", "optuna", "cmaes",
        "foxglove-sdk~=0.30.3",  # --live; its server's logs and its stop are what fsr_bringup.live.server expects
        "fsr_sim", "fsr_control", "fsr_estimation",
    ],
    zip_safe=False,
    maintainer="fsr developers",
    maintainer_email="fsr@example.org",
    description="Runner (fsr-fly), MCAP recorder (fsr-record), analysis (fsr-analyze), in-process closed loop, "
                "sweeps (fsr-sweep), tuning (fsr-tune)",
    license="Apache-2.0",
    tests_require=["pytest"],
    entry_points={
        "console_scripts": [
            "fsr-fly = fsr_bringup.cli.entry_points:fly",
            "fsr-record = fsr_bringup.recording.recorder_node:main",
            "fsr-analyze = fsr_bringup.cli.entry_points:analyze",
            "fsr-compile = fsr_bringup.cli.compile_cli:main",
            "fsr-sweep = fsr_bringup.cli.sweep_cli:main",
            "fsr-tune = fsr_bringup.cli.tune_cli:main",
            "fsr-vehicle = fsr_bringup.cli.vehicle_cli:main",
        ],
        # Scenario sections this package validates (fsr_sim.config.scenario.registered_sections).
        "fsr.scenario_sections": [
            "visualization = fsr_bringup.visualization.config:visualization_config",
        ],
    },
)
