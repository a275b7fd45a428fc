"""Frames of one trial rendered by the simulator: four key moments (start, just after the push,
just after the goal moved, the end) and a short animated GIF.

:class:`FrameRecorder` is the ``on_step`` callback of :func:`.trials.run_trial`; it renders with
the simulator's CPU TinyRenderer and keeps the end-effector trail in pixel coordinates, which the
panel draws over the frames (demonstration in red, the gripper's path in blue).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from sosdyn.report.figures.style import DEMO_COLOR, method_color, new_figure, save_figure, styled

from .arm import RATE

KEY_SIZE = (480, 360)
GIF_SIZE = (320, 240)
GIF_FPS = 10                 # one frame per 0.5 s of simulated time, played 5x faster
PUSH_LAG = 0.15              # s after the push starts: the frame shows the displacement
ARROW = 0.12                 # m: length of the push arrow drawn in the frame


class FrameRecorder:
    """Renders the key frames and every ``1 / (GIF_FPS / 5)`` s a GIF frame; ``frames`` holds
    {label: (image, time, trail, demonstration, push arrow)} (pixels), ``clip`` the GIF images."""

    def __init__(self, demo_pos=None, push_force=None, gif=True):
        self.demo_pos, self.gif = demo_pos, gif
        self.push_dir = None if push_force is None else ARROW * np.asarray(push_force) / np.linalg.norm(push_force)
        self.arrow = None
        self.frames, self.clip, self.trail = {}, [], []
        self._pending = {}
        self._every = int(round(RATE * 5 / GIF_FPS))

    def __call__(self, k, t, sim, event):
        self.trail.append(sim.ee()[0])
        if event in ("start", "goal", "end"):
            self._key({"start": "start", "goal": "goal moved", "end": "end"}[event], t, sim)
        if event == "push":
            self._pending[k + int(round(PUSH_LAG * RATE))] = "push"
            self.arrow = (self.trail[-1], self.trail[-1] + self.push_dir) if self.push_dir is not None else None
        if k in self._pending:
            self._key(self._pending.pop(k), t, sim)
        if self.gif and k % self._every == 0:
            self.clip.append(sim.render(GIF_SIZE))

    def _key(self, label, t, sim):
        img = sim.render(KEY_SIZE)
        trail = sim.to_pixels(np.array(self.trail))
        demo = None if self.demo_pos is None else sim.to_pixels(self.demo_pos)
        arrow = sim.to_pixels(np.array(self.arrow)) if label == "push" and self.arrow is not None else None
        self.frames[label] = (img, t, trail, demo, arrow)


@styled
def key_frames_figure(frames: dict, titles: dict, method: str):
    """The key frames side by side (2 x 2), trail and demonstration drawn over them."""
    labels = [k for k in ("start", "push", "goal moved", "end") if k in frames]
    fig = new_figure(9.6, 7.4)
    axes = fig.subplots(2, 2).ravel()
    for ax, label in zip(axes, labels):
        img, t, trail, demo, arrow = frames[label]
        ax.imshow(img)
        if demo is not None:
            ax.plot(demo[:, 0], demo[:, 1], color=DEMO_COLOR, lw=1.2, alpha=0.8)
        ax.plot(trail[:, 0], trail[:, 1], color=method_color(method), lw=1.6)
        if arrow is not None:                      # the push: from where it started, along the force
            ax.annotate("", xy=arrow[1], xytext=arrow[0],
                        arrowprops=dict(arrowstyle="-|>", color="#D55E00", lw=2.2, mutation_scale=18))
        when = f"at t = {t - PUSH_LAG:.1f} s, shown {1e3 * PUSH_LAG:.0f} ms later" if label == "push" else f"t = {t:.1f} s"
        ax.set_title(f"{titles.get(label, label)} ({when})")
        ax.set_axis_off()
    for ax in axes[len(labels):]:
        ax.set_axis_off()
    return fig


def save_key_frames(frames, titles, method, out_base) -> dict:
    """The panel as SVG/PNG and each raw frame as ``<out_base>_<label>.png``."""
    out_base = Path(out_base)
    for label, (img, *_rest) in frames.items():
        Image.fromarray(img).save(out_base.with_name(f"{out_base.name}_{label.replace(' ', '_')}.png"))
    return save_figure(key_frames_figure(frames, titles, method), out_base, dpi=110)


def save_gif(clip, path, caption: str = "") -> Path:
    """The clip as an animated GIF (``GIF_FPS`` frames per second), ``caption`` written on it."""
    images = []
    for i, img in enumerate(clip):
        im = Image.fromarray(img)
        draw = ImageDraw.Draw(im)
        draw.text((6, 4), f"{caption}  t = {i * 5 / GIF_FPS:.1f} s", fill=(20, 20, 20))
        images.append(im.convert("P", palette=Image.ADAPTIVE, colors=128))
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    images[0].save(path, save_all=True, append_images=images[1:], duration=int(1000 / GIF_FPS), loop=0,
                   optimize=True)
    return path
