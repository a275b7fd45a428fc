"""Running a fitted model outside the fit, one module per job for the first-order core and one per
other family: the one-state predictor for control loops (``predictor``), standalone code generation
(``export_python``: numpy-only Python, ``export_cpp``: header-only C++17, sharing ``codegen``), the
states a model is handed and the speed limit (``states``); the pose model's (``pose``) and the
second-order model's (``second_order``) predictor and exports.
"""
