"""The model's bodies and geoms as rerun entities: paths, shapes, relative poses."""

import mujoco
import numpy as np
import rerun as rr

from jugglerl.recording.geometry import (
    PLANE_HALF_WIDTH,
    body_paths,
    geom_colour,
    geom_shape,
    moving_bodies,
    multiply,
    relative_poses,
    rotate,
    xyzw,
)
from jugglerl_envs import JuggleEnv


def moved_model():
    """The scene with every joint away from zero, so every relative pose is non-trivial."""
    env = JuggleEnv()
    env.reset(seed=0)
    data = mujoco.MjData(env.model)
    data.qpos[:] = env.data.qpos
    data.qpos[:6] += [0.3, -0.4, 0.5, -0.6, 0.7, -0.8]
    data.qpos[-4:] = np.array([0.9, 0.1, -0.3, 0.2]) / np.linalg.norm([0.9, 0.1, -0.3, 0.2])
    mujoco.mj_kinematics(env.model, data)
    return env.model, data


def test_relative_poses_compose_back_to_the_world_poses():
    model, data = moved_model()
    translations, quaternions = relative_poses(model, data.xpos[None], data.xquat[None])
    world_pos, world_quat = np.zeros((model.nbody, 3)), np.zeros((model.nbody, 4))
    world_quat[0] = (1, 0, 0, 0)
    wxyz = np.roll(quaternions[0], 1, axis=-1)
    for body in range(1, model.nbody):  # compose along the tree, as the viewer does
        parent = model.body_parentid[body]
        world_pos[body] = world_pos[parent] + rotate(world_quat[parent], translations[0, body])
        world_quat[body] = multiply(world_quat[parent], wxyz[body])
    assert np.allclose(world_pos, data.xpos, atol=1e-12)
    same_rotation = np.abs(np.sum(world_quat * data.xquat, axis=1))  # q and -q are one rotation
    assert np.allclose(same_rotation, 1.0, atol=1e-12)


def test_bodies_without_joints_sit_at_their_model_offset():
    model, data = moved_model()
    translations, quaternions = relative_poses(model, data.xpos[None], data.xquat[None])
    cup = model.body("cup").id
    assert cup not in moving_bodies(model)
    assert np.allclose(translations[0, cup], model.body_pos[cup], atol=1e-12)
    assert np.allclose(quaternions[0, cup], xyzw(model.body_quat[cup]), atol=1e-7)


def test_entity_paths_mirror_the_body_tree():
    model = JuggleEnv().model
    paths = body_paths(model, "episodes/3/world")
    assert paths[model.body("ball").id] == "episodes/3/world/ball"
    assert paths[model.body("upper_arm_link").id] == (
        "episodes/3/world/base/shoulder_link/upper_arm_link"
    )


def test_primitive_geoms_become_the_matching_rerun_shapes():
    model = JuggleEnv().model
    shapes = {model.geom(g).name: geom_shape(model, g) for g in range(model.ngeom)}
    assert isinstance(shapes["ball"], rr.Ellipsoids3D)
    assert isinstance(shapes["cup_plate_0"], rr.Boxes3D)
    assert isinstance(shapes["wrist_1"], rr.Cylinders3D)
    upper_arm = shapes["upper_arm"]
    assert isinstance(upper_arm, rr.Capsules3D)
    half_length = model.geom_size[model.geom("upper_arm").id][1]
    # rerun's capsule starts at its origin: shifted back by half a length to be centred
    assert np.allclose(upper_arm.lengths.as_arrow_array().to_pylist(), [2 * half_length])
    assert np.allclose(upper_arm.translations.as_arrow_array().to_pylist(), [[0, 0, -half_length]])


def test_the_floor_is_drawn_dark_and_no_wider_than_the_arm_needs():
    """MuJoCo draws the floor in its checker texture (dark blue), not its material's white."""
    model = JuggleEnv().model
    floor = model.geom("floor").id
    red, green, blue, alpha = geom_colour(model, floor)
    assert max(red, green, blue) < 100 and blue > red and alpha == 255  # 0.1-0.4 in the XML
    half_sizes = geom_shape(model, floor).half_sizes.as_arrow_array().to_pylist()[0]
    assert model.geom_size[floor][0] > PLANE_HALF_WIDTH  # the model's floor is 6 m wide
    assert np.allclose(half_sizes[:2], [PLANE_HALF_WIDTH] * 2)
    assert tuple(geom_colour(model, model.geom("ball").id)) == tuple(
        np.round(model.geom_rgba[model.geom("ball").id] * 255)
    )  # geoms without a material keep their own colour
