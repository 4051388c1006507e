"""Flight logs: loading (.mat, MCAP, CSV), validation and writing as MCAP."""
