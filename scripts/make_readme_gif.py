"""The picture at the top of README: the same scripted grasp with soft fingers (SoftGrasp-v3), with
the rigid twin (SoftGraspRigid-v3) and with the torsional peer (SoftGraspRigidTorsion-v3), side
by side, through the lift and the carry test: the tissue holds the cylinder through the sway,
the rigid two-point grasp lets it swing out, and the rigid fingers with the tissue's patch-sized
spinning friction hold it as the tissue does.

    .venv/bin/python scripts/make_readme_gif.py                    # -> docs/images/grasp.gif
    .venv/bin/python scripts/make_readme_gif.py --seed 1009 --out /tmp/grasp.gif

Needs Pillow (it comes with the [plots] extra's matplotlib). The GIF is kept small (a few hundred
kB): every --every-th env step, 64 colours, frames of 240 x 180 each.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from softgrasp_env.policies import ScriptedGraspPolicy
from softgrasp_env.registration import make_as as make

ROOT = Path(__file__).resolve().parents[1]
PANELS = (("SoftGrasp-v3", "soft fingers (tissue)"), ("SoftGraspRigid-v3", "rigid fingers"),
          ("SoftGraspRigidTorsion-v3", "rigid + torsional friction"))


def episode_frames(env_id: str, seed: int, every: int, size: tuple[int, int], camera: dict) -> tuple[list, dict]:
    """Frames of one scripted episode as (image, info, terminated, time [s]): the reset's and
    every ``every``-th step's, the last one always; and the last info."""
    env = make(env_id, render_mode="rgb_array", render_width=size[0], render_height=size[1], **camera)
    policy = ScriptedGraspPolicy.for_env(env)
    try:
        obs, info = env.reset(seed=seed)
        rate = env.unwrapped.control_frequency
        frames, step, done = [(env.render(), info, False, 0.0)], 0, False
        while not done:
            obs, _, terminated, truncated, info = env.step(policy(obs))
            step, done = step + 1, terminated or truncated
            if step % every == 0 or done:
                frames.append((env.render(), info, terminated, step / rate))
    finally:
        env.close()
    return frames, info


def label(img: np.ndarray, text: str, status: str):
    """The frame with ``text`` at the top left and ``status`` under it (Pillow's default font)."""
    from PIL import Image, ImageDraw

    im = Image.fromarray(img)
    draw = ImageDraw.Draw(im)
    for k, line in enumerate((text, status)):
        draw.text((6, 4 + 12 * k), line, fill=(20, 20, 20))
    return im


def status(info: dict, t: float, terminated: bool) -> str:
    if terminated and not info.get("is_success"):
        what = "dropped: tilted past 45 deg"
    elif info.get("carrying"):
        what = "carry: the arm sways it"
    elif info.get("is_success"):
        what = "held through the carry"
    elif info.get("held"):
        what = "lifted"
    elif info.get("lift_height", 0.0) > 0.005:
        what = "lifting"
    else:
        what = "reaching, gripping"
    return f"t = {t:3.1f} s  {what}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python scripts/make_readme_gif.py", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    parser.add_argument("--seed", type=int, default=1006,
                        help="the start and the carry's sway (1006: the rigid grasp lifts the cylinder and loses it "
                             "in the carry, 2.75 Hz)")  # fmt: skip
    parser.add_argument("--every", type=int, default=3, help="env steps between frames (20 steps = 1 s)")
    parser.add_argument("--width", type=int, default=240)
    parser.add_argument("--height", type=int, default=180)
    parser.add_argument("--colours", type=int, default=64)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "images" / "grasp.gif")
    ns = parser.parse_args(argv)
    try:
        from PIL import Image
    except ImportError:
        parser.error("needs Pillow: pip install pillow (or the [plots] extra)")
    # One camera for every panel, fixed on the cylinder's start: the sway shows as motion.
    camera = {"render_camera": "fixed", "camera_distance": 0.42, "camera_yaw": 20.0, "camera_pitch": -20.0}
    panels = []
    for env_id, title in PANELS:
        frames, info = episode_frames(env_id, ns.seed, ns.every, (ns.width, ns.height), camera)
        print(f"{env_id}: {len(frames)} frames, success {info['is_success']}")
        panels.append([label(img, title, status(inf, t, term)) for img, inf, term, t in frames])
    n = max(len(p) for p in panels)
    panels = [p + [p[-1]] * (n - len(p)) for p in panels]  # an episode that ended early shows its end
    sheet = []
    for k in range(n):
        row = Image.new("RGB", (ns.width * len(panels), ns.height), (255, 255, 255))
        for j, panel in enumerate(panels):
            row.paste(panel[k], (j * ns.width, 0))
        sheet.append(row.quantize(colors=ns.colours, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE))
    ns.out.parent.mkdir(parents=True, exist_ok=True)
    durations = [150] * (n - 1) + [2000]  # hold the last frame
    sheet[0].save(ns.out, save_all=True, append_images=sheet[1:], duration=durations, loop=0, optimize=True)
    print(f"wrote {ns.out} ({ns.out.stat().st_size / 1e3:.0f} kB, {n} frames)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
