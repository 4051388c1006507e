"""MCAP recorder node (fsr-record)."""
