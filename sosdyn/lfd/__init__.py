"""Learning from demonstrations: data, the CDSP estimator, its convex steps, rollouts, model files.

Modules, bottom up: ``data`` and ``rollout``; ``contraction`` (fields, metric, G_k as numbers
and polynomial matrices); ``gmm``; ``certificate`` (certify, check, collapse diagnostic);
``steps`` (one convex step per module); ``refine`` (the mixture); ``learner`` (the stages as
functions on arrays); ``params``, ``model_io`` (the file), ``model_state`` (its state);
``warp`` (a diffeomorphic pre-warp); ``rounds`` (fits made of several fits); ``cdsp`` (the
estimator); ``model_files`` (loading a model file).
"""
from .cdsp import CDSP
from .data import Demonstration, Demonstrations, check_demonstrations
from .demo_files import load_demos
from .lasa import lasa_names, load_lasa
from .model_files import load_model, save_model
from .rollout import Trajectory, rollout

__all__ = ["CDSP", "Demonstration", "Demonstrations", "check_demonstrations", "lasa_names",
           "load_demos", "load_lasa", "load_model", "save_model", "Trajectory", "rollout"]
