"""Helpers of ``python -m problems bench`` / ``bench-sos``: problem definitions, timing, reports."""
