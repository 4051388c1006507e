from setuptools import find_packages, setup

package_name = "fsr_sim"

setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["test"]),
    package_data={package_name: ["config/vehicles/*.yaml", "config/scenarios/*.yaml", "config/*.xml"]},
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
    ],
    # runtime Python dependencies (the ROS message packages and rclpy are <exec_depend>s in package.xml,
    # installed from pip by requirements.txt); ros-rosidl-parser: message classes from the contract's type
    # names. MCAP recordings (fsr_sim.recording) are the 'recording' extra: a controller or estimator node on
    # a companion computer installs fsr_sim without them.
    install_requires=["setuptools", "numpy", "scipy", "numba", "PyYAML", "ros-rosidl-parser"],
    extras_require={"recording": ["mcap", "mcap-ros2-support"]},
    zip_safe=False,
    maintainer="fsr developers",
    maintainer_email="fsr@example.org",
    description="Multirotor plant, rotors, aerodynamics, disturbances and the simulator node",
    license="Apache-2.0",
    tests_require=["pytest"],
    entry_points={
        "console_scripts": [
            "simulator = fsr_sim.nodes.simulator_node:main",
        ],
    },
)
