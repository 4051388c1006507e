"""ROS 2 nodes of fsr_control (thin adapters around the algorithm modules)."""
