"""Experiments: one module per experiment, each with ``main(argv=None)``; make targets call them."""
