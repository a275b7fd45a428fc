"""The method colours: one distinct, colour-blind-safe hue per method of the report."""
import itertools

import numpy as np
import pytest

from problems.settings import METHOD_ORDER
from sosdyn.report import figures as F

# Machado, Oliveira & Fernandes (2009), severity 1, on linear RGB.
CVD = {"normal": np.eye(3),
       "deuteranopia": np.array([[0.367322, 0.860646, -0.227968], [0.280085, 0.672501, 0.047413],
                                 [-0.011820, 0.042940, 0.968881]]),
       "protanopia": np.array([[0.152286, 1.052583, -0.204868], [0.114503, 0.786281, 0.099216],
                               [-0.003882, -0.048116, 1.051998]])}


def lab(hex_color: str, vision: str = "normal") -> np.ndarray:
    """CIELAB (D65) of an sRGB colour as seen with ``vision``."""
    c = np.array([int(hex_color[i:i + 2], 16) / 255 for i in (1, 3, 5)])
    lin = np.clip(CVD[vision] @ np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4), 0, 1)
    xyz = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]) @ lin
    t = xyz / np.array([0.95047, 1.0, 1.08883])
    f = np.where(t > 0.008856, np.cbrt(t), 7.787 * t + 16 / 116)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def test_lab_of_known_colours():
    assert lab("#FFFFFF") == pytest.approx([100, 0, 0], abs=0.05)
    assert lab("#000000") == pytest.approx([0, 0, 0], abs=1e-9)
    # a pure red and a pure green differ by ~170 for normal vision, far less for a deuteranope
    assert np.linalg.norm(lab("#FF0000") - lab("#00FF00")) > 150
    assert np.linalg.norm(lab("#FF0000", "deuteranopia") - lab("#00FF00", "deuteranopia")) < 60


def test_every_report_method_has_its_own_fixed_colour():
    colors = [F.method_color(m, METHOD_ORDER) for m in METHOD_ORDER]
    assert len(set(colors)) == len(METHOD_ORDER)
    assert all(m.lower() in F.METHOD_COLORS for m in METHOD_ORDER)


def test_method_colours_are_far_apart_also_for_colour_blind_readers():
    """Pairwise CIELAB distance: >= 30 (clearly different) for normal vision, >= 15 under
    simulated deuteranopia and protanopia (the old palette had CDSP-cubic, GMR and SEDS-like
    three greens at distance ~20 and DMP / CLF-DM two oranges at 33 / 18)."""
    colors = {m: F.method_color(m, METHOD_ORDER) for m in METHOD_ORDER}
    for vision, floor in (("normal", 30), ("deuteranopia", 15), ("protanopia", 15)):
        for (a, ca), (b, cb) in itertools.combinations(colors.items(), 2):
            d = np.linalg.norm(lab(ca, vision) - lab(cb, vision))
            assert d >= floor, (vision, a, b, d)


def test_method_hues_differ():
    """Chromatic colours at least 20 degrees apart in CIELAB hue, or 30 apart in lightness."""
    colors = {m: lab(F.method_color(m, METHOD_ORDER)) for m in METHOD_ORDER}
    for (a, la), (b, lb) in itertools.combinations(colors.items(), 2):
        if min(np.hypot(*la[1:]), np.hypot(*lb[1:])) < 15:      # black: no hue
            continue
        dh = abs(np.degrees(np.arctan2(la[2], la[1]) - np.arctan2(lb[2], lb[1]))) % 360
        assert min(dh, 360 - dh) >= 20 or abs(la[0] - lb[0]) >= 30, (a, b)
