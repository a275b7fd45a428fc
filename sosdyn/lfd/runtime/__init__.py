"""Running a fitted model outside the fit: the one-state predictor for control loops
(``predictor``) and standalone code generation (``export``: numpy-only Python, header-only C++17).
"""
