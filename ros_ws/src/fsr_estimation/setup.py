from setuptools import find_packages, setup

package_name = "fsr_estimation"

setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
    ],
    install_requires=["setuptools", "numpy", "scipy", "fsr_sim"],
    # fsr-estimate's figures and its MCAP logs; the estimator node needs neither
    extras_require={"cli": ["matplotlib", "fsr_sim[recording]"]},
    zip_safe=False,
    maintainer="fsr developers",
    maintainer_email="fsr@example.org",
    description="Momentum-based external wrench estimator, whole-log analysis and the estimator node",
    license="Apache-2.0",
    tests_require=["pytest"],
    entry_points={
        "console_scripts": [
            "estimator = fsr_estimation.nodes.estimator_node:main",
            "fsr-estimate = fsr_estimation.cli.estimate_cli:main",
        ],
        # Scenario sections this package validates (fsr_sim.config.scenario.registered_sections).
        "fsr.scenario_sections": [
            "estimator = fsr_estimation.config.estimator_config:estimator_config",
        ],
    },
)
