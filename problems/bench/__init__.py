"""The benchmarks: ``learner`` (``make bench``: where the CDSP learner spends its time) and ``sos``
(``make bench-sos``: the SOS layer against SumOfSquares.py and Drake, with the sparsity rows),
with their problems and helpers."""
