"""The test harness (not part of any installed package): graph-test helpers and fixtures, and the network
lab of namespaces, shared by the packages' tests, the top-level tests and the benchmarks that need them
(``tests/`` is on pytest's ``pythonpath``; a benchmark puts it on ``sys.path`` itself). No test code runs on
import."""
