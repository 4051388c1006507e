"""ROS 2 nodes (thin adapters around fsr_estimation.core)."""
