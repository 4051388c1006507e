"""Test helpers shared by the packages' tests and the top-level graph tests (no test code runs on import)."""
