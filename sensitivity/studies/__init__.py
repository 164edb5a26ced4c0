"""Runnable sensitivity studies, one per file (``fig2``: the paper's Fig. 2 Monte Carlo)."""
