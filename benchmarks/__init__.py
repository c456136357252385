"""Benchmarks: domain families, the naive baseline, the table (``python -m benchmarks.run``)."""
