"""The estimator section of a scenario."""
