"""Momentum observer algorithms (numpy/scipy only, no rclpy)."""
