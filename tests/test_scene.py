"""The MJCF scene: UR5e kinematics, cup, ball and collision set-up."""

import mujoco
import numpy as np

from jugglerl_envs import JuggleEnv, scene

# Published UR5e DH figures (metres): d1, |a2|, |a3|, d4, d5, d6.
UR5E_LINKS = [0.1625, 0.425, 0.3922, 0.1333, 0.0997, 0.0996]


def test_joint_anchor_distances_match_ur5e_dh():
    model = scene.load_model(-9.81, 0.002, 0.035, 0.1)
    data = mujoco.MjData(model)
    rng = np.random.default_rng(0)
    for _ in range(5):  # any pose: anchor distances are rigid
        data.qpos[:6] = rng.uniform(-np.pi, np.pi, 6)
        mujoco.mj_kinematics(model, data)
        points = [data.body("base").xpos]
        points += [data.joint(name).xanchor for name in scene.ARM_JOINTS[1:]]
        points.append(data.site("flange").xpos)
        distances = [np.linalg.norm(b - a) for a, b in zip(points[:-1], points[1:], strict=True)]
        np.testing.assert_allclose(distances, UR5E_LINKS, atol=0.01)


def test_arm_has_menagerie_joint_names_and_three_learnable_servos():
    model = scene.load_model(-2.0, 0.002, 0.035, 0.1)
    names = [model.joint(i).name for i in range(6)]
    assert names == list(scene.ARM_JOINTS)
    assert [model.joint(model.actuator_trnid[i, 0]).name for i in range(3)] == list(
        scene.ACTUATED_JOINTS
    )
    plates = [
        model.geom(i).name for i in range(model.ngeom) if model.geom(i).name.startswith("cup_plate")
    ]
    assert len(plates) == 8


def test_only_the_ball_collides():
    model = scene.load_model(-2.0, 0.002, 0.035, 0.1)
    ball = model.geom("ball").id
    for geom in range(model.ngeom):
        if geom != ball:
            assert model.geom_contype[geom] == 0, model.geom(geom).name
    assert model.geom_contype[ball] & model.geom_conaffinity[model.geom("floor").id]


def test_ball_dropped_into_still_cup_from_half_a_metre_stays_in(hold):
    env = JuggleEnv(drop_height=0.5, gravity=-9.81)
    env.reset(seed=0)
    lowest_in_cup = np.inf
    for _ in range(150):  # 3 s
        _, _, terminated, _, info = env.step(hold(env))
        assert not terminated
        if info["in_cup"]:
            radial, height = env.ball_in_cup_frame()
            lowest_in_cup = min(lowest_in_cup, height)
    assert info["in_cup"] and info["catches"] == 1
    # Resting on the plates, not sunk through them: the 40° cone holds a 35 mm ball ~40 mm up.
    radial, height = env.ball_in_cup_frame()
    assert radial < 0.005 and 0.03 < height < 0.05
    assert lowest_in_cup > 0.02  # never tunnelled towards the throat on impact
