"""Test oracles shared by the tests and the benchmarks (not shipped with wetcloth): the NumPy
reference of the explicit step, the accuracy scenes and their references, the stability check.
The benchmarks import them with ``tests/`` on ``sys.path`` (``bench/_paths.py``)."""
