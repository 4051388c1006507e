"""ROS 2 nodes (thin adapters around fsr_estimation.estimator and its compiled core)."""
