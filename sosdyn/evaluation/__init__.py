"""Evaluation of learned motions: accuracy metrics and the perturbation protocol."""
