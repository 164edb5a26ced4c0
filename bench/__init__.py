"""Benchmarks: each prints its figures as ratios against a baseline measured in the same run.

The machine this runs on is shared and noisy, so absolute times are reported for information
only; the ratios are what the targets in ``docs/benchmarks.md`` are checked against.
"""
