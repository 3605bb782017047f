"""The rendered frame (softgrasp_env/render.py): the follow camera keeps the gripper and the
cylinder in the picture wherever they start (the fixed camera of 0.3 cut the palm off at the top in
4 of 4 random starts), the camera's keywords are checked and do what they say, the ground is a
checkerboard that shows motion. Measured from the renderer's own segmentation of the frame, so
every body is told apart by id, not by colour."""

from __future__ import annotations

import numpy as np
import pytest

W, H = 160, 120


def _frame_bodies(env):
    """(image, {visual kind + index: mask}) of the last render: a mask per rigid part drawn."""
    img = env.render()
    r = env.unwrapped._renderer
    seg = r.last_segmentation
    masks = {f"{v.kind}{k}": seg == body for k, (v, body) in enumerate(r.mirror_bodies)}
    if r.particle_bodies:
        masks["tissue"] = np.isin(seg, r.particle_bodies)
    return img, masks


def _touches_border(mask: np.ndarray) -> bool:
    return bool(mask[0].any() or mask[-1].any() or mask[:, 0].any() or mask[:, -1].any())


@pytest.mark.parametrize("env_id", ["SoftGrasp-v5", "SoftGraspRigid-v3"])
def test_the_follow_camera_frames_gripper_and_cylinder_at_every_start(env_id, make_env, scripted):
    env = make_env(env_id, render_mode="rgb_array", render_width=W, render_height=H)
    for seed in range(4):
        env.reset(seed=seed)
        img, masks = _frame_bodies(env)
        assert img.shape == (H, W, 3) and len(masks) >= 4  # cylinder, palm, two cores (and the tissue)
        assert masks["cylinder0"].sum() > 20 and masks["box1"].sum() > 20, seed  # cylinder and palm seen
        for name, mask in masks.items():  # (a soft core may hide behind its own tissue)
            assert not _touches_border(mask), (seed, name)  # nothing cut off
    # through a grasp and lift: the bodies move together, the camera with them
    obs, _ = env.reset(seed=1000)
    for _ in range(60):
        obs, *_ = env.step(scripted(obs))
    _, masks = _frame_bodies(env)
    assert masks["cylinder0"].sum() > 20 and not any(_touches_border(m) for m in masks.values())


def test_the_fixed_camera_sees_the_whole_start(make_env):
    env = make_env("SoftGrasp-v5", render_mode="rgb_array", render_camera="fixed", render_width=W, render_height=H)
    for seed in range(4):
        env.reset(seed=seed)
        _, masks = _frame_bodies(env)
        assert masks["cylinder0"].sum() > 5 and masks["box1"].sum() > 5, seed
        assert not any(_touches_border(m) for m in masks.values()), seed


def test_camera_keywords_move_the_camera(make_env):
    def cylinder_pixels(**kwargs) -> int:
        env = make_env("SoftGraspRigid-v3", render_mode="rgb_array", render_width=W, render_height=H, **kwargs)
        env.reset(seed=0)
        _, masks = _frame_bodies(env)
        return int(masks["cylinder0"].sum())

    near = cylinder_pixels()
    assert 0 < cylinder_pixels(camera_distance=1.5) < near / 4  # farther: smaller
    assert cylinder_pixels(camera_target=(0.9, 0.9, 0.5), camera_distance=0.1) == 0  # looking elsewhere
    assert cylinder_pixels(camera_yaw=-60.0, camera_pitch=-60.0) > 0


@pytest.mark.parametrize("kwargs, name", [({"render_camera": "orbit"}, "render_camera"),
                                          ({"camera_distance": 0.0}, "camera_distance"),
                                          ({"camera_pitch": 90.0}, "camera_pitch"),
                                          ({"camera_yaw": float("nan")}, "camera_yaw"),
                                          ({"camera_target": (0.0, 0.0)}, "camera_target"),
                                          ({"camera_target": "up"}, "camera_target"),
                                          ({"camera_target": (0.0, 0.0, 5.0)}, "camera_target")])  # fmt: skip
def test_bad_camera_keywords_are_named(kwargs, name):
    import gymnasium as gym

    with pytest.raises(ValueError, match=name):
        gym.make("SoftGraspRigid-v3", **kwargs)


def test_the_ground_is_a_checkerboard(make_env):
    """Two tones of grey alternate on the ground, so a camera that follows the bodies still shows
    them move."""
    env = make_env("SoftGraspRigid-v3", render_mode="rgb_array", render_width=W, render_height=H)
    env.reset(seed=0)
    img = env.render().astype(int)
    seg = env.unwrapped._renderer.last_segmentation
    ground = img[seg == 0]  # body 0 in the viewer: the ground
    grey = ground[(np.abs(ground[:, 0] - ground[:, 2]) < 20)].mean(axis=1)
    assert len(grey) > 1000 and np.percentile(grey, 90) - np.percentile(grey, 10) > 20


def test_the_readme_gif_script_draws_every_grasp(tmp_path):
    PIL = pytest.importorskip("PIL")
    from scripts import make_readme_gif

    out = tmp_path / "g.gif"
    assert make_readme_gif.main(["--every", "25", "--width", "64", "--height", "48", "--out", str(out)]) == 0
    im = PIL.Image.open(out)
    assert im.size == (3 * 64, 48) and im.n_frames == 5  # three panels; reset + steps 25, 50, 75, 100 (the rigid one padded)
