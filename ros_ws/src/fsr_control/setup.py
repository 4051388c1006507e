from setuptools import find_packages, setup

package_name = "fsr_control"

setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
    ],
    install_requires=["setuptools", "numpy", "scipy", "fsr_sim", "fsr_estimation"],
    zip_safe=False,
    maintainer="fsr developers",
    maintainer_email="fsr@example.org",
    description="Trajectory planner, geometric and Voliro controllers and the controller node",
    license="Apache-2.0",
    tests_require=["pytest"],
    entry_points={
        "console_scripts": [
            "controller = fsr_control.nodes.controller_node:main",
        ],
        # Scenario sections this package validates (fsr_sim.config.scenario.registered_sections).
        "fsr.scenario_sections": [
            "controller = fsr_control.config.controller_config:controller_config",
            "trajectory = fsr_control.config.controller_config:controller_config",
        ],
    },
)
