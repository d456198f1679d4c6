"""A MuJoCo model's bodies and primitive geoms as rerun entities.

Entity paths mirror the body tree under a world path (``world/base/shoulder_link/...``; a body
of the world body, like the ball, sits at ``world/<name>``), and each geom is a child of its
body's entity, placed by a static transform. Only bodies with joints move: their transforms
relative to the parent body are sent per frame (``relative_poses``), the others once.

MuJoCo quaternions are (w, x, y, z); rerun's are (x, y, z, w).
"""

from __future__ import annotations

import mujoco
import numpy as np
import rerun as rr

#: Filled shapes read better than wireframes in the viewer.
SOLID = rr.components.FillMode.Solid
#: Half width (m) up to which a plane is drawn: the arm reaches less than 1 m, and a larger floor
#: would only make the viewer's default framing take in empty floor.
PLANE_HALF_WIDTH = 1.2
#: Index of the colour texture in ``model.mat_texid`` (MuJoCo's ``mjTEXROLE_RGB``).
RGB_TEXTURE = int(mujoco.mjtTextureRole.mjTEXROLE_RGB)


def body_paths(model: mujoco.MjModel, world_path: str) -> list[str]:
    """Entity path of every body, indexed by body id (body 0 is ``world_path`` itself)."""
    paths = [world_path]
    for body in range(1, model.nbody):  # MuJoCo orders parents before children
        paths.append(f"{paths[model.body_parentid[body]]}/{model.body(body).name or body}")
    return paths


def moving_bodies(model: mujoco.MjModel) -> np.ndarray:
    """Ids of the bodies that move relative to their parent (those with joints)."""
    return np.flatnonzero(model.body_jntnum > 0)


def log_static_scene(stream: rr.RecordingStream, model: mujoco.MjModel, world_path: str) -> None:
    """Log every geom's shape and the poses of bodies without joints, once (static).

    A body without joints sits at its fixed offset in its parent (``body_pos``, ``body_quat``);
    the moving ones get their transforms per frame.
    """
    paths = body_paths(model, world_path)
    stream.log(world_path, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    for body in np.flatnonzero(model.body_jntnum == 0)[1:]:  # [1:]: not the world body
        offset = rr.Transform3D(
            translation=model.body_pos[body], quaternion=xyzw(model.body_quat[body])
        )
        stream.log(paths[body], offset, static=True)
    for geom in range(model.ngeom):
        shape = geom_shape(model, geom)
        if shape is None:
            continue
        path = f"{paths[model.geom_bodyid[geom]]}/{model.geom(geom).name or f'geom_{geom}'}"
        placement = rr.Transform3D(
            translation=model.geom_pos[geom], quaternion=xyzw(model.geom_quat[geom])
        )
        stream.log(path, placement, shape, static=True)


def geom_shape(model: mujoco.MjModel, geom: int):
    """The rerun archetype drawing a primitive geom in its own frame; ``None`` for meshes etc."""
    size = model.geom_size[geom]
    kind = model.geom_type[geom]
    style = {"colors": [geom_colour(model, geom)], "fill_mode": SOLID}
    if kind == mujoco.mjtGeom.mjGEOM_BOX:
        return rr.Boxes3D(half_sizes=[size], **style)
    if kind == mujoco.mjtGeom.mjGEOM_PLANE:  # a thin slab just below the plane's surface
        half_sizes = [  # size 0: an infinite plane
            min(size[0] or PLANE_HALF_WIDTH, PLANE_HALF_WIDTH),
            min(size[1] or PLANE_HALF_WIDTH, PLANE_HALF_WIDTH),
            0.001,
        ]
        return rr.Boxes3D(half_sizes=[half_sizes], centers=[[0, 0, -0.001]], **style)
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        return rr.Ellipsoids3D(radii=[size[0]], **style)
    if kind == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
        return rr.Ellipsoids3D(half_sizes=[size], **style)
    if kind == mujoco.mjtGeom.mjGEOM_CYLINDER:
        return rr.Cylinders3D(lengths=[2 * size[1]], radii=[size[0]], **style)
    if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:  # rerun's starts at the origin, MuJoCo's is centred
        return rr.Capsules3D(
            lengths=[2 * size[1]], radii=[size[0]], translations=[[0, 0, -size[1]]], **style
        )
    return None


def geom_colour(model: mujoco.MjModel, geom: int) -> np.ndarray:
    """RGBA (0-255) as MuJoCo draws it: the material's colour when the geom has one, tinted by
    the mean colour of the material's texture (the floor's checker is dark blue, not white)."""
    material = model.geom_matid[geom]
    if material < 0:
        return np.round(model.geom_rgba[geom] * 255).astype(np.uint8)
    rgba = model.mat_rgba[material].copy()
    texture = model.mat_texid[material, RGB_TEXTURE]
    if texture >= 0:
        rgba[:3] *= texture_mean_rgb(model, texture)
    return np.round(rgba * 255).astype(np.uint8)


def texture_mean_rgb(model: mujoco.MjModel, texture: int) -> np.ndarray:
    """Mean RGB (0-1) of a texture's texels."""
    channels = model.tex_nchannel[texture]
    size = model.tex_height[texture] * model.tex_width[texture] * channels
    start = model.tex_adr[texture]
    texels = model.tex_data[start : start + size].reshape(-1, channels)
    return texels[:, :3].mean(axis=0) / 255.0


def relative_poses(
    model: mujoco.MjModel, xpos: np.ndarray, xquat: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Pose of every body in its parent's frame, for frames of world poses.

    ``xpos`` ``[F, nbody, 3]`` and ``xquat`` ``[F, nbody, 4]`` (MuJoCo's ``data.xpos``/``xquat``,
    w first). Returns translations ``[F, nbody, 3]`` and rerun quaternions ``[F, nbody, 4]``
    (x, y, z, w).
    """
    parent = model.body_parentid
    parent_conj = xquat[:, parent] * np.array([1.0, -1.0, -1.0, -1.0])
    translations = rotate(parent_conj, xpos - xpos[:, parent])
    return translations, xyzw(multiply(parent_conj, xquat))


def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton products of (w, x, y, z) quaternions, elementwise over leading axes."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=-1,
    )


def rotate(quaternion: np.ndarray, vector: np.ndarray) -> np.ndarray:
    """Rotate 3-vectors by unit (w, x, y, z) quaternions, elementwise over leading axes."""
    w = quaternion[..., :1]
    u = quaternion[..., 1:]
    t = 2.0 * np.cross(u, vector)
    return vector + w * t + np.cross(u, t)


def xyzw(quaternion: np.ndarray) -> np.ndarray:
    """MuJoCo's (w, x, y, z) to rerun's (x, y, z, w), along the last axis."""
    return np.roll(np.asarray(quaternion), -1, axis=-1)
