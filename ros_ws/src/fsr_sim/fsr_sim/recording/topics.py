"""The topics of an fsr flight (relative names: a vehicle namespace moves them all) and their types.

One list for everything that records or reads a flight: the recorder node subscribes to these, the
analysis decodes them, an in-process flight writes them. Producers: ``odom``, ``wrench_truth``,
``sim_status`` the simulator; ``rotor_cmd``, ``wrench_cmd``, ``wrench_shortfall``, ``reference``,
``attitude_cmd``, ``wrench_desired`` the controller; ``wrench_estimate``, ``mass_estimate`` the estimator;
``goal`` a user. ``/clock`` is absolute (one per run).
"""

from __future__ import annotations

FLIGHT_TOPICS: dict[str, str] = {
    "odom": "nav_msgs/msg/Odometry",
    "wrench_truth": "geometry_msgs/msg/WrenchStamped",
    "rotor_cmd": "sensor_msgs/msg/JointState",
    "wrench_cmd": "geometry_msgs/msg/WrenchStamped",
    "wrench_shortfall": "geometry_msgs/msg/WrenchStamped",
    "reference": "trajectory_msgs/msg/MultiDOFJointTrajectory",
    "attitude_cmd": "geometry_msgs/msg/QuaternionStamped",
    "wrench_desired": "geometry_msgs/msg/WrenchStamped",
    "goal": "geometry_msgs/msg/PoseStamped",
    "wrench_estimate": "geometry_msgs/msg/WrenchStamped",
    "mass_estimate": "std_msgs/msg/Float64",
    "sim_status": "std_msgs/msg/String",
}
CLOCK_TOPIC = ("/clock", "rosgraph_msgs/msg/Clock")
